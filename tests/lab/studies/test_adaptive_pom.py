"""The adaptive-POM study's comparison at equal error: POM's cost at an error is interpolated on its curve (log-log,
never the next grid point), a POM setting that costs more and is less accurate is never the one picked, an error
outside POM's curve gives no ratio, and the per-map verdict follows the bootstrap interval."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.lab.studies.adaptive_pom import compare
from wgpuviewer.lab.studies.adaptive_pom.measure import CONFIGS, ViewData, rays


def test_pom_cost_is_interpolated_between_the_settings_around_the_error():
    errors, costs = np.array([1.0, 0.1, 0.01]), np.array([4.0, 16.0, 64.0])
    cost, why = compare.pom_cost_at(errors, costs, 0.1)
    assert why == "" and cost == pytest.approx(16.0)
    # halfway in log(error + EPS) between 16 and 64 layers: the geometric mean of their costs
    target = np.sqrt((0.1 + compare.EPS) * (0.01 + compare.EPS)) - compare.EPS
    assert compare.pom_cost_at(errors, costs, target)[0] == pytest.approx(32.0)


def test_a_costlier_less_accurate_pom_is_never_picked_and_outside_the_curve_there_is_no_ratio():
    errors, costs = np.array([1.0, 0.05, 0.2, 0.01]), np.array([4.0, 16.0, 32.0, 64.0])
    assert compare.pom_cost_at(errors, costs, 0.05)[0] == pytest.approx(16.0)  # not 32, whose error is 0.2
    assert compare.pom_cost_at(errors, costs, 2.0) == (pytest.approx(np.nan, nan_ok=True), "coarser")
    assert compare.pom_cost_at(errors, costs, 0.001)[1] == "finer"


def synthetic_view(name: str, angle: float, adaptive_scale: float, rng) -> ViewData:
    """A view where POM n layers has error 1/n and fetches n per ray, and every adaptive setting has POM 16's error
    at ``adaptive_scale`` times its fetches."""
    _, tile_of = rays((16, 8))
    tiles = int(tile_of.max()) + 1
    errors, tile_max = [], []
    for config in CONFIGS:
        p = dict(config.params)
        n = p.get("layers", 16)
        fetches = n if config.technique == "pom" else 16 * adaptive_scale
        errors.append(rng.uniform(0.9, 1.1, tile_of.size) / n)
        tile_max.append(np.full(tiles, fetches))
    return ViewData(name, angle, np.array(errors), np.array(tile_max), tile_of, np.zeros(len(CONFIGS)),
                    np.array([t.mean() for t in tile_max]))


def test_the_verdict_follows_the_ratio_and_degenerate_maps_stay_apart():
    rng = np.random.default_rng(1)
    views = [synthetic_view("bricks", a, 0.5, rng) for a in (30.0, 60.0)] + \
            [synthetic_view("spike", a, 2.0, rng) for a in (30.0, 60.0)] + [synthetic_view("bricks", 0.0, 9.0, rng)]
    rows = compare.compare(views, resamples=10)
    main = {r["heightmap"]: r for r in rows if r["config"] == "adaptive 4-32"}
    assert main["bricks"]["verdict"] == "adaptive cheaper" and main["bricks"]["views"] == 2  # 0° does not count
    assert main["bricks"]["ratio"] == pytest.approx(0.5, rel=0.1)
    assert main["spike"]["degenerate"] and main["spike"]["verdict"] == "POM cheaper"
    assert main[compare.TEXTURED]["ratio"] == pytest.approx(main["bricks"]["ratio"])  # spike left out of it
