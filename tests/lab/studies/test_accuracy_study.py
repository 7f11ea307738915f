"""The accuracy study (``wgpuviewer accuracy``): its options are checked before a folder is made, docs/accuracy.md's
blocks made from hand-made results have the expected cells, and its smoke suite writes results.csv, shadows.csv,
report.md and a fresh stamp."""

from __future__ import annotations

import math

import pytest

from wgpuviewer.cli import main
from wgpuviewer.lab.harness import stamp
from wgpuviewer.lab.harness.study import discover
from wgpuviewer.lab.studies.accuracy import docs
from wgpuviewer.lab.studies.accuracy.report import label
from wgpuviewer.lab.studies.accuracy.run import RESULTS, SHADOWS


def result(technique, params, angle, p95, worst, fetches, capped=0.0):
    return {"heightmap": "bumps", "width": 16, "height": 8, "height_scale": 0.05, "rays": 64, "angle": angle,
            "technique": technique, "params": params, "error_mean": 0.5 * p95, "error_p95": p95, "error_max": worst,
            "fetches_mean": fetches, "fetches_p95": fetches + 1, "capped": capped}


def shadow(heightmap, wrong, soft, fetches):
    return {"heightmap": heightmap, "technique": "pom", "elevation": 30.0, "light_azimuth": 150.0,
            "view_angle": 45.0, "rays": 64, "valid_rays": 60, "ref_lit": 0.8, "hard_wrong": 0.5,
            "hard_wrong_own_hit": wrong, "soft_diff": 0.9, "soft_diff_own_hit": soft, "hard_fetches": fetches,
            "soft_fetches": 99.0, "view_fetches": 77.0, "capped": 0.0}


@pytest.fixture
def committed(tmp_path):
    """A checkout whose benchmarks/accuracy holds a tiny hand-made run."""
    folder = tmp_path / docs.RUN
    folder.mkdir(parents=True)
    RESULTS.write(folder / "results.csv", [
        result("pom", "layers=8", 0.0, 0.0123, 4.5, 3.71),
        result("pom", "layers=8", 60.0, 12.34, 56.78, 9.04, capped=0.25),
        result("relief", "linear_steps=32, binary_steps=8", 0.0, 0.0, 0.0021, 18.66),
        result("relief", "linear_steps=32, binary_steps=8", 60.0, 0.25, 7.0, 17.2, capped=0.0005),
        result("maxmip", "-", 0.0, math.nan, math.nan, 1.0, capped=1.0),
        result("maxmip", "-", 60.0, 0.001, 0.002, 12.0),
    ])
    SHADOWS.write(folder / "shadows.csv", [shadow("bumps", 0.01, 0.01, 9.0), shadow("step", 0.03, 0.02, 10.0)])
    stamp.write(folder, {"definition": stamp.DEFINITION, "source": "run", "command": "wgpuviewer accuracy --out x",
                         "adapter": "Test GPU", "date": "2026-01-02T03:04:05Z", "seconds": 90.0, "parts": {}})
    return tmp_path


def test_the_blocks_of_a_hand_made_run(committed):
    """Every setting in order, p95 before max, the capped share and the run's facts; the shadow cells are the mean
    over the maps of the own hit's wrong states (the worst map in brackets), soft difference and fetches."""
    blocks = {b.name: b for b in docs.BLOCKS}
    assert {b.page for b in docs.BLOCKS} == {"docs/accuracy.md"} and set(blocks) == {
        "accuracy run", "accuracy tables", "accuracy self-shadowing"}
    assert blocks["accuracy tables"].body(committed).strip().splitlines() == [
        "## bumps (16x8)", "",
        "| technique | params | 0° | 60° |",
        "|---|---|---|---|",
        "| pom | layers=8 | 0.012 / 4.500 · 3.7 | 12.3 / 56.8 · 9.0 · 25.0% capped |",
        "| relief | linear_steps=32, binary_steps=8 | 0.000 / 0.002 · 18.7 | 0.250 / 7.000 · 17.2 · <0.1% capped |",
        "| maxmip | - | – / – · 1.0 · 100.0% capped | 0.001 / 0.002 · 12.0 |",
    ]
    assert blocks["accuracy self-shadowing"].body(committed).strip().splitlines() == [
        "64 random rays per map at 45° from the normal (random azimuths), lights at azimuth 150°, on bumps, step.", "",
        "| technique | light 30° |",
        "|---|---|",
        "| pom | 2.00 % (3.00) / 0.0150 · 9.5 |",
    ]
    assert blocks["accuracy run"].body(committed).strip() == (
        "`wgpuviewer accuracy --out x` on Test GPU, 2026-01-02, 1.5 minutes: height_scale 0.05; 16x8 maps; 64 random "
        "rays per map and angle (uniform entry points, random azimuth, seed 0), the same rays for every setting. Its "
        "report: [`benchmarks/accuracy/report.md`](../benchmarks/accuracy/report.md).")


@pytest.mark.parametrize("options, message", [
    (["--heightmaps", "nope"], "--heightmaps: unknown builtin 'nope'"),
    (["--heightmaps", "bumps", "bumps"], "--heightmaps: bumps given twice"),
    (["--rays", "0"], "--rays 0: expected 1 to"),
    (["--texels", "0"], "--texels 0: expected 1 to"),
    (["--height-scale", "nan"], "--height-scale nan: expected a relief depth"),
])
def test_options_are_checked_before_the_folder_is_made(tmp_path, capsys, options, message):
    out = tmp_path / "run"
    assert main(["accuracy", "--out", str(out), *options]) == 2
    assert message in capsys.readouterr().err and not out.exists()


@pytest.mark.requires_gpu
def test_smoke_run_writes_results_report_and_a_fresh_stamp(tmp_path):
    from wgpuviewer.relief.accuracy import DEFAULT_SETTINGS, measure, shadowing_techniques
    from wgpuviewer.textures import builtin_height

    assert "accuracy" in [s.name for s in discover()]
    out = tmp_path / "run"
    argv = ["accuracy", "--heightmaps", "bumps", "--texels", "32", "--rays", "64", "--suite", "smoke", "--quiet",
            "--out", str(out)]
    assert main(argv) == 0
    rows = RESULTS.read(out / "results.csv")
    assert [(r["technique"], r["params"], r["angle"]) for r in rows] == [
        (t, label(p), a) for t, p in DEFAULT_SETTINGS for a in (30.0, 80.0)]
    assert all(r["heightmap"] == "bumps" and (r["width"], r["height"], r["rays"]) == (32, 32, 64) for r in rows)
    assert all(r["error_p95"] <= r["error_max"] for r in rows if not math.isnan(r["error_max"]))
    pom = next(r for r in rows if r["technique"] == "pom" and r["params"] == "layers=8" and r["angle"] == 80.0)
    expected = measure("pom", builtin_height("bumps", (32, 32)), 80.0, rays=64, layers=8)
    assert pom["error_p95"] == pytest.approx(expected.error_p95, rel=1e-5, abs=1e-9)
    assert pom["fetches_mean"] == pytest.approx(expected.fetches_mean, rel=1e-5)
    shadows = SHADOWS.read(out / "shadows.csv")
    assert [(r["technique"], r["elevation"]) for r in shadows] == [(t, 45.0) for t in shadowing_techniques()]
    report = (out / "report.md").read_text(encoding="utf-8")
    assert report.startswith("# Probe accuracy") and "- adapter: **" in report and "- suite: `smoke`" in report
    assert "## bumps (32x32)" in report and "## Self-shadowing" in report
    record = stamp.read(out)
    assert record["command"] == "wgpuviewer " + " ".join(argv)
    assert {"code wgpuviewer/lab/studies/accuracy", "technique pom", "entry probe"} <= set(record["parts"])
    assert stamp.fingerprint(stamp.Files(stamp.CHECKOUT), record["parts"]) == record["parts"]  # fresh
