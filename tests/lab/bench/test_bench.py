"""Benchmark: parameter sweeps from the registry, view geometry against the renderer, the
report's selection logic, and the smoke suite end to end (what CI runs)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.relief.technique_folder import technique_folder
from wgpuviewer.lab.bench import report as bench_report
from wgpuviewer.lab.bench import run as bench
from wgpuviewer.lab.bench.plots import pareto_front
from wgpuviewer.lab.bench.view import (
    FOV,
    MAX_FOOTPRINT,
    bilinear,
    eval_grid,
    load_heightmap,
    make_view,
)
from wgpuviewer.relief.accuracy import simd_tile_cost
from wgpuviewer.relief.reference import sample_bilinear
from wgpuviewer.relief.renderer import DrawConfig, Renderer  # imports wgpu before the log fixture touches its logger
from wgpuviewer.techniques import TECHNIQUES

# --- sweeps come from the registry ---------------------------------------------------------------

def test_every_registered_technique_is_benchmarked_with_valid_params():
    configs = bench.configs_for(list(TECHNIQUES), bench.SWEEPS)
    assert configs[0][0] == bench.BASELINE
    assert {name for name, _ in configs} == set(TECHNIQUES)
    for name, params in configs:
        assert set(params) == {p.name for p in TECHNIQUES[name].params}


BRAND_NEW = '''"""A technique the benchmark has no sweep for."""

from wgpuviewer.core.params import Param
from wgpuviewer.techniques import Technique

TECHNIQUE = Technique("brand_new", "x", "", "", ("albedo",), (Param("steps", 7, 1, 99, int, ""),), ray_search=True,
                      order=1000)
'''


def test_unknown_technique_runs_its_defaults_and_stale_sweeps_are_skipped(tmp_path):
    with technique_folder(tmp_path, "brand_new", BRAND_NEW):
        assert bench.settings_for("brand_new", bench.SWEEPS) == [{"steps": 7}]
        # a sweep naming a parameter the technique no longer has is dropped, not an error
        sweeps = {"brand_new": ({"layers": 8}, {"steps": 9})}
        assert bench.settings_for("brand_new", sweeps) == [{"steps": 9}]
        assert bench.settings_for("brand_new", {"brand_new": ({"layers": 8},)}) == [{"steps": 7}]


def test_table41_layer_counts_are_in_both_suites():
    for suite in bench.SUITES.values():
        layers = {s.get("layers") for s in suite.sweeps["pom"]}
        assert {4, 8, 16, 24, 32} <= layers
        assert {0.0, 45.0, 60.0, 80.0} <= set(suite.angles)


# --- view geometry ------------------------------------------------------------------------------

@pytest.mark.parametrize("angle", [0.0, 45.0, 80.0, 89.0])
def test_view_angle_footprint_and_centre(tmp_path, angle):
    hm = load_heightmap("bricks", 64, tmp_path)
    view = make_view(hm, angle, (64, 36))
    assert view.angle_min - 0.1 <= angle <= view.angle_max + 0.1
    assert view.angle_max - view.angle_min < FOV * 1.2
    v = view.v_ts
    np.testing.assert_allclose(np.linalg.norm(v, axis=-1), 1.0, atol=1e-12)
    # the frame centre sees the middle of a tile (where spike/wall/step put their feature)
    centre = (view.uv0[17, 31] + view.uv0[18, 32]) / 2
    np.testing.assert_allclose(np.mod(centre, 1.0), 0.5, atol=0.05)
    # no pixel minifies the texture: every fetch is a mip level 0 fetch
    texels = view.uv0 * 64
    step = max(np.abs(np.diff(texels, axis=0)).max(), np.abs(np.diff(texels, axis=1)).max())
    assert step <= MAX_FOOTPRINT + 1e-6
    # the plane holds every entry point plus its longest parallax offset
    uv_scale = np.asarray(view.scene.materials["relief"].uv_scale)
    span = 0.05 * np.hypot(v[..., 0], v[..., 1]) / v[..., 2]
    assert (view.uv0 - span[..., None] > 0).all() and (view.uv0 + span[..., None] < uv_scale).all()


def test_bilinear_matches_the_reference_sampler():
    rng = np.random.default_rng(0)
    tex = rng.random((5, 7))
    uv = rng.uniform(-2, 3, (200, 2))
    np.testing.assert_allclose(bilinear(tex[..., None], uv)[:, 0], sample_bilinear(tex, uv), atol=1e-12)


def test_eval_grid_is_bounded():
    rows, cols = eval_grid((1920, 1080), 32768)
    assert rows.size <= 32768 and rows.max() < 1080 and cols.max() < 1920
    assert eval_grid((3, 2), 100)[0].size == 6


def test_entry_uv_matches_the_rendered_uv(tmp_path, gpu):
    """The benchmark's per-pixel entry uv (CPU) is the uv the GPU interpolates: basic's hit uv."""
    hm = load_heightmap("bumps", 64, tmp_path)
    for angle in (30.0, 85.0):
        view = make_view(hm, angle, (80, 45))
        image = Renderer(view.scene, gpu).render("basic", view.size)
        assert image.covered.all()
        err = np.abs(image.data[..., :2] - view.uv0).max() * 64
        assert err < 0.05, (angle, err)


def test_a_scikit_image_map_is_downscaled_written_and_drawn_from_its_file(tmp_path, gpu):
    """The real maps (the smoke suite's brick; the smoke test below runs builtins only) load area-downscaled to
    ``real_size``, go to the scene as a PNG file and draw with the view's entry uv."""
    if not bench.skimage_available():
        pytest.skip("scikit-image is not installed (the test extra has it)")
    hm = load_heightmap("brick", 64, tmp_path, real_size=96)
    assert max(hm.size) == 96 and hm.height.dtype == np.float32 and 0 <= hm.height.min() < hm.height.max() <= 1
    assert "downscaled to" in hm.source
    (png,) = tmp_path.glob("skimage_brick_*.png")
    assert str(png) in hm.texture
    view = make_view(hm, 45.0, (40, 24))
    image = Renderer(view.scene, gpu).render("basic", view.size)
    assert image.covered.all()
    assert np.abs(image.data[..., :2] - view.uv0).max() * 96 < 0.05


# --- report logic -------------------------------------------------------------------------------

def _row(technique, params, angle, ratio, p95, heightmap="m", ms=None):
    return {"technique": technique, "params": params, "angle": angle, "ratio_to_basic": ratio,
            "uv_err_p95": p95, "fetches_mean": 1.0, "heightmap": heightmap, "gpu_ms": ms or ratio}


def test_headline_picks_the_cheapest_configuration_within_each_budget():
    rows = [
        _row("basic", "-", 0, 1.0, 0.4), _row("basic", "-", 45, 1.0, 9.0),
        _row("pom", "layers=8", 0, 1.5, 0.1), _row("pom", "layers=8", 45, 1.6, 0.7),
        _row("pom", "layers=32", 0, 2.5, 0.05), _row("pom", "layers=32", 45, 2.6, 0.2),
        _row("pom", "layers=32", 89, 2.6, 50.0),  # beyond the headline's angles
    ]
    best = {h["budget"]: h for h in bench_report.headline(rows)}
    assert best[0.25]["config"] == ("pom", "layers=32")
    assert best[1.0]["config"] == ("pom", "layers=8")
    assert math.isclose(best[1.0]["ratio"], math.sqrt(1.5 * 1.6))
    assert bench_report.headline([_row("basic", "-", 0, 1.0, 5.0)])[0]["config"] is None


def test_headline_lists_configurations_close_to_the_winner():
    """Within CLOSE_MARGIN of the winner's time (a tie on a noisy adapter) a configuration is listed beside it;
    one just outside is not, nor one that misses the budget."""
    rows = [_row("distance_refined", "iterations=256", 45, 1.65, 0.0), _row("auto", "max_error=0.5", 45, 1.69, 0.4),
            _row("quadmax", "-", 45, 1.65 * (1 + bench_report.CLOSE_MARGIN) + 0.01, 0.0),
            _row("pom", "layers=8", 45, 1.60, 0.9)]
    best = {h["budget"]: h for h in bench_report.headline(rows)}
    assert best[0.5]["config"] == ("distance_refined", "iterations=256")
    assert [m["config"] for m in best[0.5]["close"]] == [("auto", "max_error=0.5")]
    assert best[0.25]["close"] == []  # auto's 0.4 misses 0.25
    # at 1 texel POM (1.60) wins; 1.68 is the margin: distance_refined (1.65) is close, auto (1.69) is not
    assert best[1.0]["config"] == ("pom", "layers=8")
    assert [m["config"][0] for m in best[1.0]["close"]] == ["distance_refined"]


def test_equal_error_speedup_uses_the_cheapest_pom_at_least_as_accurate():
    rows = [_row("pom_adaptive", "-", 45, 1.2, 0.3, ms=1.2),
            _row("pom", "layers=8", 45, 1.0, 0.9, ms=1.0),
            _row("pom", "layers=16", 45, 1.5, 0.25, ms=1.5),
            _row("pom", "layers=32", 45, 2.0, 0.1, ms=2.0)]
    (s,) = bench_report.equal_error_speedups(rows)
    assert s["pom"]["params"] == "layers=16" and math.isclose(s["speedup"], 1.5 / 1.2)


def test_pareto_front():
    pts = [(1, 5), (2, 2), (3, 3), (4, 1), (2, 6)]
    assert pareto_front(pts) == [0, 1, 3]


def test_headline_reports_simd_cost_against_the_reference_configuration():
    rows = []
    for angle, (d_ratio, d_simd, a_ratio, a_simd) in {0: (2.0, 4.0, 1.0, 0.0), 45: (4.0, 20.0, 2.0, 6.0)}.items():
        rows += [{**_row("distance", "iterations=256", angle, d_ratio, 0.0), "fetches_simd": d_simd},
                 {**_row("auto", "max_error=0.5", angle, a_ratio, 0.3), "fetches_simd": a_simd}]
    best = {h["budget"]: h for h in bench_report.headline(rows)}
    assert best[0.5]["config"] == ("auto", "max_error=0.5") and best[0.5]["simd"] == 3.0
    assert best[0.25]["config"] == ("distance", "iterations=256") and best[0.25]["simd"] == 12.0
    ref = bench_report.reference_cost(rows)
    assert math.isclose(ref["ratio"], math.sqrt(8.0)) and ref["simd"] == 12.0
    # a run without the SIMD column (the H100 CSV) has no SIMD cost, not a wrong one
    old = [{k: v for k, v in r.items() if k != "fetches_simd"} for r in rows]
    assert math.isnan(bench_report.headline(old)[1]["simd"])


def test_cost_correlation_picks_the_better_predictor():
    rng = np.random.default_rng(1)
    simd = rng.uniform(1, 50, 40)
    mean = simd * rng.uniform(0.3, 1.0, 40)  # divergence differs between rows
    rows = [{"ratio_to_basic": 1 + 0.1 * s, "fetches_mean": m, "fetches_simd": s} for s, m in zip(simd, mean)]
    c = bench_report.cost_correlation(rows)
    assert c["rows"] == 40 and math.isclose(c["simd"], 1.0) and c["mean"] < c["simd"]
    assert bench_report.cost_correlation([{"ratio_to_basic": 1.0, "fetches_mean": 1.0,
                                           "fetches_simd": float("nan")}])["rows"] == 0


def test_fetch_percentile_from_counts_is_numpys():
    from wgpuviewer.lab.bench.capture import percentile_of_counts

    rng = np.random.default_rng(0)
    for n in (1, 2, 7, 1000):
        x = rng.integers(0, 40, n)
        for q in (0, 5, 50, 95, 100):
            assert math.isclose(percentile_of_counts(np.bincount(x), q), np.percentile(x, q), abs_tol=1e-9)
    assert math.isnan(percentile_of_counts(np.zeros(3, np.int64), 95))


def test_old_results_without_the_new_columns_read_as_missing(tmp_path):
    header = ",".join(c for c in bench.COLUMNS if c not in ("fetches_simd", "simd_tile", "map_bytes"))
    line = ("full,brick,512x512,pom,layers=8,45,44,46,1920x1080,NVIDIA H100 80GB HBM3 (DiscreteGPU) via Vulkan,"
            "Vulkan,timestamp,50,1.5,1,1.5,8,9,0.1,0.2,0.3,40,0,1,100")
    path = tmp_path / "old.csv"
    path.write_text(header + "\n" + line + "\n")
    (row,) = bench.TABLE.read(path)
    assert row["ratio_to_basic"] == 1.5 and math.isnan(row["fetches_simd"]) and row["simd_tile"] == ""
    assert row["frames"] == 50 and row["map_bytes"] is None
    assert list(row) == list(bench.COLUMNS)
    bench.rereport([path], tmp_path / "again")
    report = (tmp_path / "again" / "report.md").read_text()
    assert "| ≤ 1 | pom layers=8 | 1.50 | 8.0 | n/a |" in report  # no SIMD-tile cost measured: n/a, not 0
    assert "2 of their TPCs" in report  # the H100's graphics: ratios meaningful, milliseconds not
    assert "- date: not recorded in the results; report regenerated from old.csv" in report


def test_committed_runs_still_read_and_report(tmp_path):
    """Every results.csv committed under benchmarks/ by a benchmark run reads back (the first H100 runs lack the
    newer columns) and regenerates a report."""
    from pathlib import Path

    runs = [p for p in (Path(__file__).resolve().parents[3] / "benchmarks").glob("*/results.csv")
            if p.read_text().startswith("suite,heightmap,")]
    assert runs
    for path in runs:
        rows = bench.TABLE.read(path)
        assert rows and all(r["gpu_ms"] > 0 for r in rows), path
    bench.rereport(runs[:1], tmp_path)
    assert (tmp_path / "report.md").read_text().startswith("# wgpuviewer benchmark")


# --- the GPU part: batched frames and captures ---------------------------------------------------------

def test_batched_capture_is_the_renderers_render_and_a_round_is_one_submit(tmp_path, gpu):
    """Draws of one technique with different parameters share a submit and keep their own parameters; the bench's
    fetch statistics come from exactly the data render() gives."""
    from wgpuviewer.lab.bench.capture import capture
    from wgpuviewer.lab.bench.config_timing import time_configs

    view = make_view(load_heightmap("bumps", 64, tmp_path), 60.0, (40, 24))
    renderer = Renderer(view.scene, gpu)
    configs = [("basic", {}), ("pom", {"layers": 4}), ("pom", {"layers": 32}), ("parallax", {"offset_limiting": True})]
    draws = [DrawConfig.of(n, p) for n, p in configs]
    got = capture(renderer, draws, view.size, max_bytes=2 * 40 * 24 * 20)  # two configurations per batch
    assert got.submits == 2 and got.readbacks == 4
    for draw, cap in zip(draws, got.captures):
        image = renderer.render(draw, view.size)
        assert (cap.covered == image.covered).all()
        np.testing.assert_array_equal(cap.data[cap.covered], image.data[image.covered])
    few, many = (c.data[..., 3][c.covered].mean() for c in got.captures[1:3])
    assert few < many  # 4 and 32 layers drawn in one submit kept their own layer counts
    stats = bench._fetch_stats(got.captures[2], (8, 4))
    fetches = got.captures[2].data[..., 3]
    image = np.where(fetches < 0, -fetches - 1, fetches)  # negative: capped
    assert stats["fetches_simd"] == simd_tile_cost(image, (8, 4), got.captures[2].covered)
    assert math.isclose(stats["fetches_mean"], float(image[got.captures[2].covered].mean()), rel_tol=1e-6)
    timing = time_configs(renderer, configs, view.size, frames=3, warmup=1)
    if timing.timer == "timestamp":
        # compile round + warm-up round + 3 timed rounds, one submit each, then one to resolve the timestamps;
        # one wait after the warm-up, one read-back of all timestamps
        assert timing.submits == 1 + 1 + 3 + 1 and timing.readbacks == 2
    assert all(r.median_ms > 0 for r in timing.results)


def test_map_bytes_counts_the_height_derived_maps(tmp_path, gpu):
    view = make_view(load_heightmap("bumps", 64, tmp_path), 45.0, (16, 16))
    renderer = Renderer(view.scene, gpu)
    sizes = {t: bench.map_bytes(renderer, "relief", t) for t in ("basic", "normal", "pom", "maxmip", "quadmax")}
    assert sizes["basic"] == sizes["normal"] == 0
    assert sizes["pom"] == 4 * sum((64 >> k) ** 2 for k in range(7))  # r32float with its mip chain
    quad_rows = sum((64 + (1 << k) - 1) >> k for k in range(1, 7))  # leaves + quad levels, 32 texels wide
    assert sizes["quadmax"] == sizes["pom"] + 16 * 32 * quad_rows


# --- the smoke suite, end to end ------------------------------------------------------------------

def test_cli_rejects_bad_options(tmp_path, capsys):
    from wgpuviewer.cli import main

    for argv in (["--angles", "90"], ["--heightmaps", "nope"], ["--techniques", "nope"],
                 ["--resolution", "12"], ["--frames", "0"], ["--angles", "a,b"], ["--simd-tile", "8"]):
        assert main(["bench", "--suite", "smoke", "--out", str(tmp_path), *argv]) == 2
        err = capsys.readouterr().err
        assert err.startswith("wgpuviewer: error: --") and "Traceback" not in err


#: The smoke suite narrowed by the command's options (two builtin maps, two angles, 3 frames): every technique
#: and sweep setting still runs through maps, timing, capture, reference, report and plots, in a fraction of the
#: whole suite's time (the committed llvmpipe-smoke run is the whole suite).
SMOKE_MAPS, SMOKE_ANGLES, SMOKE_FRAMES = ("bricks", "spike"), (0.0, 60.0), 3


def test_smoke_suite_writes_complete_sane_outputs(tmp_path, gpu):
    from wgpuviewer.cli import main

    out = tmp_path / "bench"
    argv = ["bench", "--suite", "smoke", "--out", str(out), "--heightmaps", ",".join(SMOKE_MAPS),
            "--angles", ",".join(f"{a:g}" for a in SMOKE_ANGLES), "--frames", str(SMOKE_FRAMES), "--quiet"]
    assert main(argv) == 0
    rows = bench.TABLE.read(out / "results.csv")
    suite = bench.SUITES["smoke"]
    configs = bench.configs_for(list(TECHNIQUES), suite.sweeps)
    assert len(rows) == len(SMOKE_MAPS) * len(SMOKE_ANGLES) * len(configs)
    assert {(r["heightmap"], r["angle"]) for r in rows} == {(m, a) for m in SMOKE_MAPS for a in SMOKE_ANGLES}
    assert list(rows[0]) == list(bench.COLUMNS)
    for r in rows:
        assert r["gpu_ms"] > 0 and r["basic_ms"] > 0 and r["adapter"] and r["frames"] == SMOKE_FRAMES
        assert r["angle_min"] - 0.1 <= r["angle"] <= r["angle_max"] + 0.1
        assert 0 <= r["capped_fraction"] <= 1 and 0 < r["covered_fraction"] <= 1
        assert r["fetches_p95"] >= 0 and r["fetches_mean"] >= 0 and r["fetches_simd"] >= 0
        assert r["simd_tile"] == "8x4" and r["map_bytes"] >= 0
        if r["eval_pixels"] > 0:
            assert 0 <= r["uv_err_mean"] <= r["uv_err_max"] and 0 <= r["uv_err_p95"] <= r["uv_err_max"]
            assert 0 < r["psnr_db"] <= 99
        if r["technique"] == "basic":
            assert r["ratio_to_basic"] == 1 and r["fetches_mean"] == 0 and r["fetches_simd"] == 0
            assert r["map_bytes"] == 0
    # the error metric sees parallax: no displacement is far off at 60°, many POM layers are close
    by = {(r["heightmap"], r["technique"], r["params"], r["angle"]): r for r in rows}
    assert by["bricks", "basic", "-", 60.0]["uv_err_p95"] > 2.0
    assert by["bricks", "pom", "layers=64", 60.0]["uv_err_p95"] < 0.25
    assert by["bricks", "pom", "layers=64", 60.0]["psnr_db"] > by["bricks", "basic", "-", 60.0]["psnr_db"]
    report = (out / "report.md").read_text()
    for section in ("## Headline", "## The thesis' experiment (Table 4.1)", "## Per height map",
                    "## Map memory per technique", "## Which cost predicts the time", "## The run", "## Plots"):
        assert section in report
    assert "SIMD-tile fetches" in report and "the SIMD-tile fetches" in report  # the comparison with distance
    assert rows[0]["adapter"] in report
    assert report.startswith("# wgpuviewer benchmark: speed against error (smoke suite)\n\n- command: "
                             f"`wgpuviewer {' '.join(argv)}`\n- adapter: **")
    if "pom_adaptive" in TECHNIQUES:
        assert "Speed-up of adaptive POM" in report
    else:
        assert "not in this build's technique registry" in report
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        assert "matplotlib is not installed" in report
    else:
        for name in ("pareto.png", "fetches_vs_angle.png", "cost_vs_time.png"):
            data = (out / name).read_bytes()
            assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) < 400_000
