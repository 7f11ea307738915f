"""Benchmark: parameter sweeps from the registry, view geometry against the renderer, the
report's selection logic, and the smoke suite end to end (what CI runs)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from wgpuviewer.bench import report as bench_report
from wgpuviewer.bench import run as bench
from wgpuviewer.bench.view import (
    FOV,
    MAX_FOOTPRINT,
    bilinear,
    eval_grid,
    load_heightmap,
    make_view,
)
from wgpuviewer.relief.reference import sample_bilinear
from wgpuviewer.relief.renderer import Renderer  # imports wgpu before the log fixture touches its logger
from wgpuviewer.relief.techniques import TECHNIQUES, Param, Technique

# --- sweeps come from the registry ---------------------------------------------------------------

def test_every_registered_technique_is_benchmarked_with_valid_params():
    configs = bench.configs_for(list(TECHNIQUES), bench.SWEEPS)
    assert configs[0][0] == bench.BASELINE
    assert {name for name, _ in configs} == set(TECHNIQUES)
    for name, params in configs:
        assert set(params) == {p.name for p in TECHNIQUES[name].params}


def test_unknown_technique_runs_its_defaults_and_stale_sweeps_are_skipped(monkeypatch):
    new = Technique("brand_new", "x", "", "", ("albedo",), (Param("steps", 7, 1, 99, int, ""),), ray_search=True)
    monkeypatch.setitem(TECHNIQUES, "brand_new", new)
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


def test_equal_error_speedup_uses_the_cheapest_pom_at_least_as_accurate():
    rows = [_row("pom_adaptive", "-", 45, 1.2, 0.3, ms=1.2),
            _row("pom", "layers=8", 45, 1.0, 0.9, ms=1.0),
            _row("pom", "layers=16", 45, 1.5, 0.25, ms=1.5),
            _row("pom", "layers=32", 45, 2.0, 0.1, ms=2.0)]
    (s,) = bench_report.equal_error_speedups(rows)
    assert s["pom"]["params"] == "layers=16" and math.isclose(s["speedup"], 1.5 / 1.2)


def test_pareto_front():
    pts = [(1, 5), (2, 2), (3, 3), (4, 1), (2, 6)]
    assert bench_report.pareto_front(pts) == [0, 1, 3]


# --- the smoke suite, end to end ------------------------------------------------------------------

def test_cli_rejects_bad_options(tmp_path, capsys):
    from wgpuviewer.cli import main

    for argv in (["--angles", "90"], ["--heightmaps", "nope"], ["--techniques", "nope"],
                 ["--resolution", "12"], ["--frames", "0"], ["--angles", "a,b"]):
        assert main(["bench", "--suite", "smoke", "--out", str(tmp_path), *argv]) == 2
        err = capsys.readouterr().err
        assert err.startswith("wgpuviewer: error: --") and "Traceback" not in err


def test_smoke_suite_writes_complete_sane_outputs(tmp_path, gpu):
    from wgpuviewer.cli import main

    out = tmp_path / "bench"
    assert main(["bench", "--suite", "smoke", "--out", str(out), "--quiet"]) == 0
    rows = bench.read_csv(out / "results.csv")
    suite = bench.SUITES["smoke"]
    maps = [m for m in suite.heightmaps if m not in bench.REAL_MAPS or bench.skimage_available()]
    configs = bench.configs_for(list(TECHNIQUES), suite.sweeps)
    assert len(rows) == len(maps) * len(suite.angles) * len(configs)
    assert list(rows[0]) == list(bench.COLUMNS)
    for r in rows:
        assert r["gpu_ms"] > 0 and r["basic_ms"] > 0 and r["adapter"] and r["frames"] == suite.frames
        assert r["angle_min"] - 0.1 <= r["angle"] <= r["angle_max"] + 0.1
        assert 0 <= r["capped_fraction"] <= 1 and 0 < r["covered_fraction"] <= 1
        assert r["fetches_p95"] >= 0 and r["fetches_mean"] >= 0
        if r["eval_pixels"] > 0:
            assert 0 <= r["uv_err_mean"] <= r["uv_err_max"] and 0 <= r["uv_err_p95"] <= r["uv_err_max"]
            assert 0 < r["psnr_db"] <= 99
        if r["technique"] == "basic":
            assert r["ratio_to_basic"] == 1 and r["fetches_mean"] == 0
    # the error metric sees parallax: no displacement is far off at 60°, many POM layers are close
    by = {(r["heightmap"], r["technique"], r["params"], r["angle"]): r for r in rows}
    assert by["bricks", "basic", "-", 60.0]["uv_err_p95"] > 2.0
    assert by["bricks", "pom", "layers=64", 60.0]["uv_err_p95"] < 0.25
    assert by["bricks", "pom", "layers=64", 60.0]["psnr_db"] > by["bricks", "basic", "-", 60.0]["psnr_db"]
    report = (out / "report.md").read_text()
    for section in ("## Headline", "## The thesis' experiment (Table 4.1)", "## Per height map", "## Plots"):
        assert section in report
    assert rows[0]["adapter"] in report
    if "pom_adaptive" in TECHNIQUES:
        assert "Speed-up of adaptive POM" in report
    else:
        assert "not in this build's technique registry" in report
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        assert "matplotlib is not installed" in report
    else:
        for name in ("pareto.png", "fetches_vs_angle.png"):
            data = (out / name).read_bytes()
            assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) < 400_000
