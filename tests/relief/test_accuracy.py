"""The cost measures of relief/accuracy.py and the writer of docs/accuracy.md."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.core.errors import InputError
from wgpuviewer.relief.accuracy import (
    DEFAULT_SETTINGS,
    measure,
    run,
    shadow_run,
    simd_tile_cost,
)
from wgpuviewer.techniques import TECHNIQUES
from wgpuviewer.textures import builtin_height


def test_simd_tile_cost_is_the_mean_of_tile_maxima():
    f = np.zeros((4, 16))
    f[0, 0] = 10  # one slow lane makes its whole 8x4 tile pay 10
    f[:, 8:] = 3
    assert simd_tile_cost(f) == pytest.approx((10 + 3) / 2)
    assert simd_tile_cost(f, tile=(1, 1)) == pytest.approx(f.mean())  # one lane per group: the plain mean


def test_simd_tile_cost_partial_tiles_and_coverage():
    f = np.arange(5 * 9, dtype=float).reshape(5, 9)
    # tiles (8x4): rows 0-3 x cols 0-7, 0-3 x 8, 4 x 0-7, 4 x 8
    expected = np.mean([f[0:4, 0:8].max(), f[0:4, 8].max(), f[4, 0:8].max(), f[4, 8]])
    assert simd_tile_cost(f) == pytest.approx(expected)
    covered = np.zeros_like(f, bool)
    covered[0, 0] = True
    assert simd_tile_cost(f, covered=covered) == 0.0  # only the covered lane counts, in the only live tile
    assert np.isnan(simd_tile_cost(f, covered=np.zeros_like(covered)))
    with pytest.raises(InputError):
        simd_tile_cost(np.zeros(5))


def test_a_run_measures_what_measure_gives(gpu):
    """A run traces the reference once per map and angle for all settings: each of its results is the measurement
    ``measure`` gives for that setting alone; a map whose every ray is capped has no error, only the capped share."""
    maps = {"step": builtin_height("step", (16, 16)), "flat1": builtin_height("flat1", (16, 8))}
    settings = (("pom", {"layers": 4}), ("maxmip", {"max_steps": 1}))
    measured = run(maps, angles=(0.0, 60.0), settings=settings, rays=32)
    assert list(measured.heightmaps) == ["step", "flat1"] and measured.heightmaps["flat1"] == np.shape(maps["flat1"])
    for name, height in maps.items():
        for i, (technique, params) in enumerate(settings):
            for angle in (0.0, 60.0):
                a, b = measured.results[name, i, angle], measure(technique, height, angle, rays=32, **params)
                assert a.fetches_mean == pytest.approx(b.fetches_mean) and a.capped == b.capped
                if np.isnan(b.error_p95):  # every ray capped
                    assert np.isnan(a.error_p95), (name, technique, angle)
                else:
                    assert a.error_p95 == pytest.approx(b.error_p95, abs=1e-6), (name, technique, angle)
    capped = measured.results["step", 1, 60.0]
    assert capped.capped == 1.0 and np.isnan(capped.error_p95)


def test_accuracy_measures_every_ray_search_technique():
    """``wgpuviewer accuracy``'s settings are the registry's: each ray-search entry's accuracy_settings, in order."""
    expected = [(name, params) for name, t in TECHNIQUES.items() if t.ray_search for params in t.accuracy_settings]
    assert list(DEFAULT_SETTINGS) == expected
    assert {name for name, _ in DEFAULT_SETTINGS} == {name for name, t in TECHNIQUES.items() if t.ray_search}
    assert {"quadmax", "quadmax_pom", "auto"} <= {name for name, _ in DEFAULT_SETTINGS}


@pytest.mark.parametrize("kwargs, message", [
    (dict(rays=0), "rays = 0; expected 1 to 4194304"),
    (dict(rays=-1), "rays = -1; expected 1 to 4194304"),
    (dict(rays=10**12), "rays = 1000000000000; expected 1 to 4194304 (32 bytes a ray"),
    (dict(rays=64.0), "rays = 64.0; expected a whole number of rays"),
    (dict(angle_deg=90.0), "angle_deg = 90.0; expected 0 <= angle < 90 degrees"),
    (dict(angle_deg=-10.0), "angle_deg = -10.0; expected 0 <= angle < 90"),
    (dict(angle_deg=1e9), "angle_deg = 1000000000.0; expected 0 <= angle < 90"),
    (dict(angle_deg=float("nan")), "angle_deg = nan"),
    (dict(angle_deg="30"), "angle_deg = '30'; expected a real number"),
    (dict(height=np.full((8, 8), 0.5 + 0j)), "height has dtype complex128; expected real numbers"),
    (dict(height_scale="0.05"), "height_scale = '0.05'; expected a real number"),
])
def test_measure_refuses_what_it_cannot_use_in_one_line_before_tracing(kwargs, message, monkeypatch):
    """Like the CLI's options: an InputError naming the argument and the range, never an IndexError, a MemoryError
    or NaN statistics; nothing is traced first."""
    import wgpuviewer.relief.accuracy as accuracy

    monkeypatch.setattr(accuracy, "exact_hit", lambda *a, **k: pytest.fail("traced before the arguments were checked"))
    args = dict(technique="pom", height=np.full((8, 8), 0.5), angle_deg=30.0, rays=64)
    args.update(kwargs)
    with pytest.raises(InputError) as error:
        measure(**args)
    text = str(error.value)
    assert text.startswith("measure: ") and message in text and "\n" not in text, text
    with pytest.raises(InputError, match="run: "):  # the accuracy table's runs check the same way
        run({"m": args["height"]}, angles=(args["angle_deg"],), settings=(("pom", {}),), rays=args["rays"],
            height_scale=args.get("height_scale", 0.05))


def test_measure_at_its_largest_angle_and_ray_counts_gives_numbers(gpu):
    a = measure("pom", np.full((8, 8), 0.5), 89.9, rays=1)
    assert a.rays == 1 and np.isfinite(a.fetches_mean)


def test_a_shadow_run_of_a_tiny_set(gpu):
    """Self-shadowing per map, technique and light: there are shadows to get right at a low light, and the exact
    tracer casts the reference's shadows from its own hits."""
    maps = {"step": builtin_height("step", (16, 16)), "bricks": builtin_height("bricks", (32, 32))}
    measured = shadow_run(maps, techniques=("pom", "maxmip"), elevations=(30.0, 60.0), rays=256)
    assert set(measured.results) == {(m, t, e) for m in maps for t in ("pom", "maxmip") for e in (30.0, 60.0)}
    lit = [m.ref_lit for m in measured.results.values() if m.elevation == 30.0]
    assert min(lit) < 1.0  # shadows to get right
    assert all(m.hard_wrong <= 0.02 for (_, t, _), m in measured.results.items() if t == "maxmip")
    assert all(0.0 <= m.hard_wrong_own_hit <= 1.0 and np.isfinite(m.hard_fetches).all() for m in measured.results.values())
