"""auto: the error budget as a technique (wgpuviewer/techniques/auto/: auto.wgsl, autotable.py, its slot). The
shader picks the bin and budget level the table was built for, runs exactly the chosen candidate's code, keeps the
p95 UV error within the budget at 0-80 degrees on the benchmark's maps and the hard cases, and its table is measured
once per material and then read from the disk cache."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.relief.accuracy import npot_height, random_rays
from wgpuviewer.relief.output import mode_data
from wgpuviewer.relief.probe import probe
from wgpuviewer.relief.reference import exact_hit, uv_error_texels, view_dir_from_angles
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.scene import load_scene
from wgpuviewer.techniques import TECHNIQUES
from wgpuviewer.techniques.auto import autotable
from wgpuviewer.techniques.auto.autotable import AUTO_BINS, AUTO_CANDIDATES, AUTO_TAN0
from wgpuviewer.textures import builtin_height

from .test_render import GOLDEN


def table_of(height: np.ndarray, height_scale: float = 0.05) -> np.ndarray:
    return autotable.measure(1.0 - np.asarray(height, np.float32), height_scale)


def test_scaled_layers_keep_the_horizontal_spacing_inside_a_bin():
    edges = autotable.edge_angles()
    for n in (4, 16, 64):
        lower = autotable.lower_edge_layers(n)
        assert lower == int(np.ceil(n / np.sqrt(2)))
        for b in range(1, len(edges) - 2):  # the scaled bins (the last one runs n as it is)
            inside = np.linspace(edges[b], edges[b + 1], 50)[1:-1]
            got = autotable.scaled_layers(n, inside)
            assert got.min() >= lower and got.max() <= n and (np.diff(got) >= 0).all()
            tan = np.tan(np.radians(inside))
            assert (got >= n * tan / np.tan(np.radians(edges[b + 1])) - 1e-9).all()  # never wider-spaced than at the edge
            assert autotable.scaled_layers(n, edges[b] + 1e-9) == lower
        assert autotable.scaled_layers(n, 0.0) == n and autotable.scaled_layers(n, 89.9) == n  # bin 0, last bin: as is


def test_bins_and_budget_levels():
    edges = autotable.edge_angles()
    # the last bin is open-ended and measured at its lower edge and at LAST_BIN_TOP
    assert len(edges) == AUTO_BINS + 1 and edges[-1] == autotable.LAST_BIN_TOP
    assert edges[0] == 0 and np.all(np.diff(edges) > 0) and 88 < edges[-2] < 89
    assert autotable.bin_of(0.0) == 0 and autotable.bin_of(89.99) == autotable.bin_of(edges[-1]) == AUTO_BINS - 1
    # just above each edge falls into the bin that starts there
    assert (autotable.bin_of(edges[1:-1] + 1e-6) == np.arange(1, AUTO_BINS)).all()
    assert autotable.bin_of(np.degrees(np.arctan(AUTO_TAN0)) - 1e-6) == 0
    levels = {m: autotable.budget_level(m) for m in (0.0625, 0.25, 0.5, 0.7, 0.99, 1.0, 8.0)}
    assert levels[0.5] == levels[0.7] == levels[0.99] == levels[1.0] - 1 == levels[0.25] + 1
    assert levels[0.0625] == 0 and autotable.budgets()[levels[8.0]] == 8.0


def test_the_shader_picks_the_tables_choice_and_runs_the_candidates_code(gpu):
    h = builtin_height("bumps", (64, 64))
    table = table_of(h)
    rng = np.random.default_rng(4)
    angles = rng.uniform(0, 89.5, 4096)
    view = view_dir_from_angles(angles, rng.uniform(0, 360, 4096))
    uv = rng.random((4096, 2))
    tested = set()
    for max_error in (0.25, 0.5, 2.0):
        got = probe("auto", h, uv, view, 0.05, max_error=max_error)
        choice = autotable.texels(table)[autotable.budget_level(max_error)][autotable.bin_of(angles), 0]
        # float32 bin arithmetic may round a ray sitting on a bin edge to the neighbouring bin
        assert np.mean(got.layers == choice + 1) > 0.995, max_error
        for index in np.unique(choice):
            name, params = AUTO_CANDIDATES[int(index)]
            tested.add(name)
            rays = got.layers == index + 1
            if name == "basic":
                np.testing.assert_array_equal(got.uv[rays], uv[rays].astype(np.float32))
                continue
            if name not in autotable.LAYER_PARAM:
                alone = probe(name, h, uv[rays], view[rays], 0.05, **params)
                np.testing.assert_array_equal(got.uv[rays], alone.uv)
                np.testing.assert_array_equal(got.fetches[rays], alone.fetches)
                continue
            # POM and relief run the count scaled with tan inside the bin (autotable.scaled_layers, in float64 here)
            key = autotable.LAYER_PARAM[name]
            layers = autotable.scaled_layers(params[key], angles[rays])
            assert layers.min() >= autotable.lower_edge_layers(params[key]) and layers.max() <= params[key]
            same = np.zeros(rays.sum(), bool)
            for n in np.unique(layers):
                sub = layers == n
                alone = probe(name, h, uv[rays][sub], view[rays][sub], 0.05, **{**params, key: int(n)})
                same[sub] = (got.uv[rays][sub] == alone.uv).all(axis=1) & (got.fetches[rays][sub] == alone.fetches)
            # float32 tan may round a ray sitting on a count's boundary to the neighbouring count
            assert same.mean() > 0.995, (max_error, params, same.mean())
    assert tested == set(autotable.COST_WEIGHTS), tested  # every method's code ran


BUDGET_MAPS = ("bricks", "bumps", "ridges", "flat0", "flat1", "spike", "step", "wall", "checker")


BUDGET_ANGLES = (0, 10, 20, 30, 45, 60, 70, 75, 80)


@pytest.mark.parametrize("name", BUDGET_MAPS)
def test_p95_within_the_budget_up_to_80_degrees(gpu, name):
    """Other rays than the table's (random entry points and azimuths, another seed) keep the p95 UV error within
    max_error at every angle 0-80 degrees."""
    size = (128, 128) if name in ("bricks", "bumps", "ridges") else (64, 64)
    h = builtin_height(name, size)
    rays = [random_rays(2048, angle, seed=angle + 1000) for angle in BUDGET_ANGLES]
    uv, view = np.concatenate([r[0] for r in rays]), np.concatenate([r[1] for r in rays])
    ref = exact_hit(1.0 - h, uv, view, 0.05)
    for max_error in (0.25, 0.5, 1.0):
        got = probe("auto", h, uv, view, 0.05, max_error=max_error)
        assert not got.capped.any()
        err = uv_error_texels(got.uv, ref.uv, size[::-1]).reshape(len(BUDGET_ANGLES), -1)
        p95 = np.percentile(err, 95, axis=1)
        assert (p95 <= max_error).all(), (max_error, dict(zip(BUDGET_ANGLES, p95.round(3))))


GRAZING_ANGLES = (85.0, 88.0, 89.0, 89.5, 89.9)


@pytest.mark.parametrize("name", BUDGET_MAPS)
def test_p95_within_the_budget_at_grazing_angles(gpu, name):
    """85-89.9 degrees, in the last bin up to the angle its upper edge is measured at: the table holds every bin to the
    budget at both ends (a candidate that meets it at the last bin's lower edge may miss it by 100 texels at 89.9
    degrees: parallax on the 128x128 spike map)."""
    size = (128, 128) if name in ("bricks", "bumps", "ridges", "spike") else (64, 64)
    h = builtin_height(name, size)
    rays = [random_rays(1024, angle, seed=int(angle * 10) + 2000) for angle in GRAZING_ANGLES]
    uv, view = np.concatenate([r[0] for r in rays]), np.concatenate([r[1] for r in rays])
    ref = exact_hit(1.0 - h, uv, view, 0.05)
    got = probe("auto", h, uv, view, 0.05, max_error=0.5)
    err = np.where(got.capped, np.inf, uv_error_texels(got.uv, ref.uv, size[::-1])).reshape(len(GRAZING_ANGLES), -1)
    p95 = np.percentile(err, 95, axis=1)
    assert (p95 <= 0.5).all(), dict(zip(GRAZING_ANGLES, p95.round(3)))


def test_npot_map_and_a_larger_relief(gpu):
    h = npot_height()
    rays = [random_rays(2048, angle, seed=5) for angle in (0, 30, 60, 80)]
    uv, view = np.concatenate([r[0] for r in rays]), np.concatenate([r[1] for r in rays])
    got = probe("auto", h, uv, view, 0.1, max_error=0.5)
    ref = exact_hit(1.0 - h, uv, view, 0.1)
    p95 = np.percentile(uv_error_texels(got.uv, ref.uv, (343, 401)).reshape(4, -1), 95, axis=1)
    assert (p95 <= 0.5).all(), p95


def test_the_table_is_measured_once_then_read_from_the_cache(gpu, monkeypatch):
    h = builtin_height("ridges", (32, 32))
    first = table_of(h)
    assert first.shape == (len(AUTO_CANDIDATES) + len(autotable.SCALED), len(autotable.edge_angles()),
                           len(autotable.FIELDS))

    def no_probe(*args, **kwargs):
        raise AssertionError("the cached table should have been used")

    monkeypatch.setattr("wgpuviewer.relief.probe.probe", no_probe)
    np.testing.assert_array_equal(autotable.measure(1.0 - h.astype(np.float32), 0.05), first)
    monkeypatch.undo()
    # another height scale is another table (the slot is scale-bound)
    assert not np.array_equal(table_of(h, 0.1), first)


def test_more_budget_never_costs_more():
    h = builtin_height("bumps", (64, 64))
    choice = autotable.choose(table_of(h))
    cost, met = choice[..., 2], choice[..., 3] > 0
    both = met[1:] & met[:-1]
    assert (cost[1:][both] <= cost[:-1][both] + 1e-9).all()
    assert met[autotable.budget_level(8.0)].all()  # 8 texels: something always meets it
    lines = autotable.describe(table_of(h), 0.5)
    assert lines[0].startswith("0.0-") and lines[-1].split(":")[0].endswith("90°")


def test_debug_view_and_registry_entry(gpu):
    """The layers mode paints the chosen candidate (1-based, cheapest first) as grey."""
    tech = TECHNIQUES["auto"]
    assert tech.ray_search and not tech.exact and "auto_table" in tech.textures
    assert [slot.name for slot in tech.slots] == ["auto_table"]  # its own slot, declared in its folder
    assert tech.fetch_bound(tech.defaults()) >= TECHNIQUES["quadmax"].fetch_bound(TECHNIQUES["quadmax"].defaults())
    assert tech.layer_range(tech.defaults()) == (1.0, float(len(AUTO_CANDIDATES)))
    renderer = Renderer(load_scene(GOLDEN / "scene.toml"), gpu)
    image = renderer.render("auto", (96, 54))
    chosen = mode_data(image, "layers")[image.covered]
    assert chosen.min() >= 1 and chosen.max() <= len(AUTO_CANDIDATES) and len(np.unique(chosen)) >= 2
