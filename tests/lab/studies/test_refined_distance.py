"""The refined-distance study: its numpy twin of the distance tracer takes the GPU tracer's steps (same fetch
counts, same hits), so the variants it measures are measured as the renderer would; the generated pits and slots;
the model of Donnelly's fixed-budget loop; the map formats' bytes; the smoke suite end to end."""

from __future__ import annotations

import numpy as np
import pytest

from maptools.cache import cached_generate
from maptools.kinds.distance_refined.slot import REFINED_BANDS, REFINED_MAX_ANGLE, REFINED_SECTORS
from maptools.volume.slot import DISTANCE_SLICES, uploaded_volume
from wgpuviewer.lab.bench.run import REAL_MAPS
from wgpuviewer.lab.studies.refined_distance import bounded, donnelly, formats, pits, reliefs
from wgpuviewer.lab.studies.refined_distance.baseline import plain_before
from wgpuviewer.lab.studies.refined_distance.report import ratios
from wgpuviewer.lab.studies.refined_distance.run import SUITES, run
from wgpuviewer.lab.studies.refined_distance.tracer import trace
from wgpuviewer.lab.studies.refined_distance.variants import CONDITION_PAIRS, PLAIN, variants
from wgpuviewer.relief.accuracy import random_rays
from wgpuviewer.relief.maps import depth_range
from wgpuviewer.relief.probe import probe
from wgpuviewer.relief.reference import exact_hit
from wgpuviewer.textures import BUILTINS, builtin_height


@pytest.mark.parametrize("name", ["bricks", "wall"])
def test_twin_takes_the_gpu_tracers_steps(gpu, name):
    h = builtin_height(name, (48, 48)).astype(np.float64)
    depth = 1.0 - h
    plain = uploaded_volume(cached_generate("distance", h, backend="auto", slices=DISTANCE_SLICES, height_scale=0.05))
    refined = cached_generate("distance_refined", h, backend="auto", slices=DISTANCE_SLICES, height_scale=0.05,
                              sectors=REFINED_SECTORS, bands=REFINED_BANDS, max_angle=REFINED_MAX_ANGLE)
    bins = {"sectors": REFINED_SECTORS, "bands": REFINED_BANDS, "max_angle": REFINED_MAX_ANGLE}
    for angle in (0.0, 33.0, 55.0, 73.0, 79.0, 84.0):  # off the band edges: float32 and float64 pick the same one
        uv, v = random_rays(1024, angle, seed=int(angle))
        uv32, v32 = uv.astype(np.float32).astype(np.float64), v.astype(np.float32).astype(np.float64)
        ref = exact_hit(depth, uv32, v32, 0.05)
        for technique, volumes, extra in (("distance", plain, {}), ("distance_refined", refined, bins)):
            gpu_result = probe(technique, h, uv, v, 0.05)
            twin = trace(depth, volumes, uv32, v32, 0.05, depth_min=depth_range(depth, gpu.depth_format)[0], **extra)
            same = gpu_result.fetches == twin.fetches
            assert same.mean() >= 0.995, (technique, angle, same.mean())
            assert abs(gpu_result.fetches.mean() - twin.fetches.mean()) <= 0.005 * twin.fetches.mean()
            assert np.allclose(twin.t, ref.t, atol=1e-4) and not twin.capped.any()  # exact, as the tracer


def test_smoke_suite(tmp_path, gpu):
    res = run("smoke", tmp_path, progress=False, command="wgpuviewer refined-distance --suite smoke")
    rows, suite, chosen = res.rows, SUITES["smoke"], variants()
    twins = [r for r in rows if r["tracer"] == "numpy twin"]
    assert len(twins) == len(suite.heightmaps) * len(suite.angles) * len(chosen)
    gpu_rows = [r for r in rows if r["tracer"] != "numpy twin"]
    assert {r["variant"] for r in gpu_rows} == {v.name for v in chosen if v.technique}
    for g in gpu_rows:  # the renderer's count agrees with the twin's on the same view
        t = next(r for r in twins if (r["heightmap"], r["angle"], r["variant"]) == (g["heightmap"], g["angle"],
                                                                                        g["variant"]))
        assert abs(g["fetches_mean"] - t["fetches_mean"]) <= 0.02 * t["fetches_mean"] + 0.05
    for r in twins:
        assert r["fetches_simd"] >= r["fetches_mean"] >= 1 and r["memory_mib"] > 0 and r["capped"] == 0
    text = (tmp_path / "report.md").read_text()
    assert text.startswith("# Distance-map variants: fetches per pixel (mean / SIMD-tile 8x4)\n\n"
                           "- command: `wgpuviewer refined-distance --suite smoke`\n"
                           f"- adapter: **{gpu.summary}**\n- suite: `smoke`\n- date: ")
    assert "## bricks" in text and "## plate" in text and "product vs before" in text and "## Grazing views" in text
    assert "## The paper's visibility condition" in text and "## Donnelly's regime" in text
    assert (tmp_path / "results.csv").read_text().startswith("heightmap,size,angle,variant")
    assert (tmp_path / "ratio_to_distance.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert all(abs(r - 1.0) < 1e-12 for (_, v, _), r in ratios(rows).items() if v == PLAIN)
    # Donnelly's regime: every budget on every measured map and angle, and the exact tracer exact
    fixed = [r for r in res.donnelly if r["regime"] == "fixed"]
    assert {r["iterations"] for r in fixed} == set(suite.budgets) and all(r["rays"] > 0 for r in res.donnelly)
    assert all(r["error_p95"] < 1e-3 for r in res.donnelly if r["regime"] == "exact")
    # the formats: every format on both paths at every size, and the GPU renderer's cost at every angle
    assert {(b["format"], b["backend"], b["size"]) for b in res.formats} == {
        (f, b, n) for f in formats.FORMATS for b in formats.BACKENDS for n in suite.format_sizes}
    assert {(c["format"], c["angle"]) for c in res.costs} == {(f, a) for f in formats.FORMATS
                                                              for a in suite.format_angles}
    assert all(c["fetches_simd"] >= c["fetches_mean"] > 0 and c["ms"] > 0 for c in res.costs)
    assert "| `distance_refined` | 1056.0 |" in text
    # the deeper plates: every plate, angle, bins and condition; the table names each plate and angle once
    assert {(r["plate"], r["angle"], r["bins"], r["visibility"]) for r in res.pits} == {
        (p.name, a, f"{s} x {n}", vis) for p in pits.PLATES for a in suite.pit_angles for s, n in pits.BINS
        for vis in ("off", "on")}
    assert all(r["fetches_mean"] >= 1 for r in res.pits)
    assert "### Deeper and wider holes" in text and (tmp_path / "pits.csv").exists()
    assert all(f"| {p.name} |" in text for p in pits.PLATES)
    # the bound: every variant at every angle on the bounded maps; the worked example with its numbers and picture
    assert {(r["heightmap"], r["angle"], r["variant"]) for r in res.bounded} == {
        (m, a, v) for m in suite.exact_maps for a in suite.exact_angles
        for v in (*bounded.PRODUCT_VARIANTS, bounded.EXACT_SINGLE, bounded.EXACT_BINNED)}
    assert all(r["fetches_mean"] >= 1 and 0 <= r["passed"] <= 1 for r in res.bounded)
    assert {m["variant"] for m in res.bounded_maps} == {bounded.EXACT_SINGLE, bounded.EXACT_BINNED}
    assert "## The paper's worked example" in text and "## The refined map bounded: exact visibility" in text
    assert (tmp_path / "worked_example.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "bounded.csv").exists() and (tmp_path / "example.csv").exists()


def test_cli_rejects_bad_options(tmp_path, capsys):
    from wgpuviewer.cli import main

    for argv in (["--angles", "90"], ["--angles", "a"], ["--heightmaps", "nope"], ["--heightmaps", ","]):
        assert main(["refined-distance", "--out", str(tmp_path), *argv]) == 2
        assert "Traceback" not in capsys.readouterr().err


def test_an_unknown_height_map_is_refused_before_the_folder_or_the_gpu(tmp_path, monkeypatch, capsys):
    from wgpuviewer.cli import main
    from wgpuviewer.core import gpu

    def no_gpu(*args, **kwargs):
        raise AssertionError("the GPU was started")

    monkeypatch.setattr(gpu, "get_gpu", no_gpu)
    out = tmp_path / "new"
    assert main(["refined-distance", "--out", str(out), "--suite", "smoke", "--heightmaps", "bricks,bogus"]) == 2
    assert capsys.readouterr().err.strip() == ("wgpuviewer: error: --heightmaps: unknown height map 'bogus'; "
                                               "expected some of " + ", ".join((*BUILTINS, *REAL_MAPS,
                                                                                 *reliefs.NAMES)))
    assert not out.exists()


@pytest.mark.parametrize("name, size", [("bricks", (40, 40)), ("wall", (40, 24)), ("spike", (17, 33)), ("flat1", (1, 1))])
def test_baseline_is_never_above_the_box_exact_map(name, size):
    """The maptools-2 map (centre distance to the cell-min solid minus half the diagonal) is a lower bound of
    the box-exact distance to the same solid (K = 1), voxel by voxel: the baseline is as safe and looser."""
    h = builtin_height(name, size).astype(np.float64)
    before = plain_before(h, slices=DISTANCE_SLICES, height_scale=0.05)
    box = cached_generate("distance", h, backend="cpu", slices=DISTANCE_SLICES, height_scale=0.05, subcells=1)
    assert before.shape == box.shape and before.dtype == np.float32
    assert (before <= box).all() and (before >= 0).all()
    if name != "flat1":
        assert before.mean() < box.mean()


def test_the_options_take_grazing_angles_and_the_generated_maps():
    import argparse

    from wgpuviewer.lab.studies.refined_distance.command import STUDY

    parser = argparse.ArgumentParser()
    STUDY.add_arguments(parser)
    args = parser.parse_args(["--out", "x", "--angles", "85,87,89", "--heightmaps", "plate,grille,bricks"])
    args.command_line = "wgpuviewer refined-distance"
    options = STUDY.options(args)
    assert options["angles"] == [85.0, 87.0, 89.0] and options["heightmaps"] == ["plate", "grille", "bricks"]
    bound = parser.parse_args(["--out", "x", "--only", "bounded"])
    bound.command_line = "wgpuviewer refined-distance --only bounded"
    assert options["only"] == "" and STUDY.options(bound)["only"] == "bounded"


def _components(mask: np.ndarray) -> list[np.ndarray]:
    """The connected (4-neighbour, wrapping) regions of ``mask``, as lists of (row, col)."""
    rows, cols = mask.shape
    seen = np.zeros_like(mask)
    out = []
    for start in zip(*np.nonzero(mask)):
        if seen[start]:
            continue
        stack, cells = [start], []
        seen[start] = True
        while stack:
            y, x = stack.pop()
            cells.append((y, x))
            for q in (((y + 1) % rows, x), ((y - 1) % rows, x), (y, (x + 1) % cols), (y, (x - 1) % cols)):
                if mask[q] and not seen[q]:
                    seen[q] = True
                    stack.append(q)
        out.append(np.array(cells))
    return out


@pytest.mark.parametrize("size", [48, 100])
def test_the_plate_has_deep_round_holes_a_few_texels_across(size):
    h = reliefs.plate(size)
    assert h.dtype == np.float32 and set(np.unique(h)) == {0.0, 1.0}
    holes = _components(h == 0)
    area = np.pi * (reliefs.PLATE_DIAMETER / 2) ** 2
    assert len(holes) >= (size / reliefs.PLATE_PITCH) ** 2 * 0.8
    for cells in holes:  # each a disc of the diameter, whole (the map tiles: holes wrap, none is cut)
        assert 0.75 * area <= len(cells) <= 1.25 * area
        extent = [np.ptp(np.unwrap(cells[:, i], period=size)) + 1 for i in (0, 1)]
        assert max(extent) <= reliefs.PLATE_DIAMETER + 1


def test_the_grille_has_deep_slots_one_to_three_texels_wide():
    h = reliefs.grille(96)
    slots = _components(h == 0)
    widths = {len(np.unique(c[:, 1])) for c in slots}
    lengths = {len(np.unique(c[:, 0])) for c in slots}
    assert widths == set(reliefs.SLOT_WIDTHS) and lengths == {reliefs.SLOT_LENGTH}
    assert set(np.unique(h)) == {0.0, 1.0}


def test_trilinear_lookup_matches_scipy_with_repeat_and_clamped_depth():
    ndimage = pytest.importorskip("scipy.ndimage")
    rng = np.random.default_rng(3)
    vol = rng.random((5, 7, 6))
    x, y, z = rng.uniform(-9, 15, 500), rng.uniform(-9, 15, 500), rng.uniform(-2, 7, 500)
    got = donnelly.trilinear(vol, x, y, z)
    # scipy's map_coordinates with one mode for all axes: repeat x, y by hand, clamp z by edge padding
    padded = np.pad(vol, ((2, 2), (0, 0), (0, 0)), mode="edge")
    tiled = np.tile(padded, (1, 6, 6))
    want = ndimage.map_coordinates(tiled, [np.clip(z, 0, 4) + 2, np.mod(y, 7) + 7, np.mod(x, 6) + 6], order=1)
    assert np.allclose(got, want, atol=1e-12)
    assert np.allclose(donnelly.trilinear(vol, np.full(3, 2.0), np.full(3, 3.0), np.array([0.0, 1.0, 4.0])),
                       vol[[0, 1, 4], 3, 2])


def test_donnellys_loop_converges_on_a_flat_floor_and_flags_rays_past_the_hit():
    """A flat floor at depth 0.6: the stored distance is exact up to the box margins, so the fixed-budget loop
    approaches the floor from above (never past it) and its error shrinks with the budget; a point placed past the
    hit is counted as passed."""
    h = np.full((16, 16), 0.4)
    depth = 1.0 - h
    vol = cached_generate("distance", h, backend="cpu", slices=DISTANCE_SLICES, height_scale=0.05)
    uv, v = random_rays(300, 60.0, seed=2)
    ref = exact_hit(depth, uv, v, 0.05)
    errors = []
    for n in (2, 8, 64):
        acc = donnelly.accuracy(donnelly.march(vol, uv, v, 0.05, n), ref.t, ref.uv, (16, 16), v, 0.05)
        assert acc.passed == 0.0 and acc.rays == 300
        errors.append(acc.p95)
    assert errors[0] > errors[1] >= errors[2] and errors[2] < 1.5
    exact = donnelly.Marched(ref.t, ref.uv)
    assert donnelly.accuracy(exact, ref.t, ref.uv, (16, 16), v, 0.05).max == 0.0
    deeper = donnelly.Marched(ref.t + 0.4, uv - v[:, :2] / v[:, 2:3] * 0.05 * (ref.t + 0.4)[:, None])
    assert donnelly.accuracy(deeper, ref.t, ref.uv, (16, 16), v, 0.05).passed == 1.0  # 0.64 texel past it


def test_format_bytes_and_extrapolated_builds(gpu):
    heights = {8: reliefs.plate(8), 16: reliefs.plate(16)}
    built = formats.measure(heights, gpu, budget_s=0.0, formats=("distance", "distance_refined", "cone"))
    by = {(b.format, b.backend, b.size): b for b in built}
    assert by["distance", "gpu", 8].bytes_per_texel == DISTANCE_SLICES * 2  # r16float (uploaded_volume)
    assert by["distance_refined", "gpu", 8].bytes_per_texel == (REFINED_SECTORS * REFINED_BANDS + 1) * \
        DISTANCE_SLICES * 2  # r16float, every bin and the plain volume
    assert by["cone", "cpu", 8].bytes_per_texel == 8  # rg32float
    for (fmt, backend, size), b in by.items():  # a zero budget runs only the smallest size
        assert b.extrapolated == (size == 16)
        if b.extrapolated:
            assert b.build_s == pytest.approx(by[fmt, backend, 8].build_s * 4)
            assert b.bytes_per_texel == by[fmt, "gpu", 8].bytes_per_texel


def test_the_condition_pairs_compare_a_map_with_itself_but_the_condition():
    """Each pair differs only in the visibility condition, "off" set explicitly; the renderer's technique sits on
    the product's bins with the kind's default."""
    from maptools.registry import get_kind
    from wgpuviewer.lab.studies.refined_distance import variants as study

    kind = get_kind("distance_refined")
    named = {v.name: v for v in variants()}
    for on, off in CONDITION_PAIRS:
        a, b = dict(named[on].options), dict(named[off].options)
        assert a.pop(study.VISIBILITY) == "on" and b.pop(study.VISIBILITY) == "off" and a == b
    default = next(o.default for o in kind.options if o.name == study.VISIBILITY)
    (product,) = [v for v in named.values() if v.technique == "distance_refined"]
    assert product.options[study.VISIBILITY] == default and product.bins()["sectors"] == REFINED_SECTORS


def test_compact_storages_round_every_value_down():
    """float16 and 8-bit stored values are never above the float32 ones (a step never grows: safety holds), and
    lose at most one float16 step / one 8-bit step of the range (values above the 8-bit range are held at it)."""
    from wgpuviewer.lab.studies.refined_distance.variants import EIGHT_BIT_RANGE, STORAGES

    rng = np.random.default_rng(5)
    v = np.concatenate([rng.random(5000) * 40.0, [0.0, EIGHT_BIT_RANGE, 1e-8, 60000.0]]).astype(np.float32)
    v64 = v.astype(np.float64)
    half, _ = STORAGES["float16"]
    eight, _ = STORAGES["8-bit"]
    h, e = half(v), eight(v)
    assert (h <= v64).all() and (e <= v64).all()
    assert (v64 - h <= np.spacing(v.astype(np.float16)).astype(np.float64) + 1e-12).all()
    assert (np.minimum(v64, EIGHT_BIT_RANGE) - e <= EIGHT_BIT_RANGE / 255 + 1e-12).all()
    assert len(np.unique(e)) <= 256
