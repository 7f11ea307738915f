"""``wgpuviewer perspective --suite smoke`` end to end (what CI runs): the files, the contract's columns, the
self-checks it records, and the answers its report gives; bad command lines fail with one clear line."""

from __future__ import annotations

import csv
import math
import signal
import subprocess
import sys
import textwrap

import pytest
from PIL import Image

from wgpuviewer import cli
from wgpuviewer.lab.studies.perspective import run as study
from wgpuviewer.lab.studies.perspective import tieback
from wgpuviewer.lab.studies.perspective.methods import METHODS, PARALLEL_THREADS
from wgpuviewer.lab.studies.perspective.report import PLOTS
from wgpuviewer.relief.renderer import Renderer  # noqa: F401 - imports wgpu before the log fixture touches its logger

REQUIRED_METHODS = {"direct", "span", "direct_rcp", "span_rcp", "incremental",
                    *(f"parallel_{k}" for k in PARALLEL_THREADS), "two_ended", "subdivided_8", "subdivided_16",
                    "adaptive_8", "adaptive_32", "hardware", "reanchor_64", "kahan", "double_single", "fixed16_16"}


@pytest.fixture(scope="module")
def smoke(tmp_path_factory, adapter):
    out = tmp_path_factory.mktemp("perspective")
    assert cli.main(["perspective", "--out", str(out), "--suite", "smoke", "--quiet"]) == 0
    return out


@pytest.fixture(scope="module")
def rows(smoke):
    return study.TABLE.read(smoke / "results.csv")


@pytest.mark.requires_gpu
def test_the_smoke_run_writes_every_output(smoke):
    for name in ("results.csv", "along_span.csv", "tieback.csv", "report.md", *PLOTS):
        assert (smoke / name).is_file(), name
    for name in PLOTS:
        with Image.open(smoke / name) as image:
            assert image.format == "PNG" and min(image.size) >= 300, name
    assert not list(smoke.glob(".*.tmp"))  # atomic writes left nothing behind


@pytest.mark.requires_gpu
def test_results_have_the_contracts_columns_and_methods(smoke, rows):
    with open(smoke / "results.csv", newline="", encoding="utf-8") as f:
        header = next(csv.reader(f))
    assert {"method", "max_err", "span_length", "precision"} <= set(header)
    assert {r["method"] for r in rows} >= REQUIRED_METHODS
    assert {r["precision"] for r in rows} == {"float32", "float64", "float32x2", "fixed16.16"}
    assert {r["sweep"] for r in rows} == {"span_length", "tile", "tilt", "magnitude", "speed", "speed_tile"}
    suite = study.SUITES["smoke"]
    assert {r["span_length"] for r in rows if r["sweep"] == "span_length"} == set(suite.span_lengths)
    assert {r["span_length"] for r in rows if r["sweep"] == "tile"} == set(suite.tile_widths)
    for r in rows:
        if r["tilt_deg"] < 90:
            assert math.isfinite(r["max_err_px"]) and math.isfinite(r["max_err"]), r
            assert r["flagged_fraction"] == 0 and r["footprint_texels"] > 0, r
        # divided evaluations per pixel: every pixel, or the anchors; not counted for the rasteriser
        assert (r["exact_per_pixel"] is None) if r["method"] == "hardware" else 0 < r["exact_per_pixel"] <= 1, r


@pytest.mark.requires_gpu
def test_every_sweep_is_at_a_texel_per_pixel_in_the_middle(rows):
    """The footprint is fixed (run.FOOTPRINT at each frame's middle pixel): pixel and texel errors are comparable
    across lengths, and the median footprint stays near it."""
    for r in rows:
        if r["sweep"] in ("span_length", "speed") and r["method"] == "direct":
            assert 0.3 < r["footprint_texels"] < 3, r


@pytest.mark.requires_gpu
def test_the_run_checks_kernels_and_compiled_loops_against_their_twins_and_flags_every_undefined_texel(gpu, rows):
    checked = [r for r in rows if r["gpu_max_ulp"] is not None]
    assert {r["method"] for r in checked} == {name for name, m in METHODS.items() if m.on_gpu}
    if gpu.software:
        assert all(r["gpu_max_ulp"] == 0 and r["gpu_flag_mismatch"] == 0 for r in checked)
    compiled = [r for r in rows if r["cpu_max_ulp"] is not None]
    assert {r["method"] for r in compiled} == set(METHODS)
    assert all(r["cpu_max_ulp"] == 0 and r["cpu_flag_mismatch"] == 0 for r in compiled)
    assert all(r["undetected"] == 0 for r in rows)
    crossing = [r for r in rows if r["sweep"] == "tilt" and r["tilt_deg"] > 90]
    assert crossing and all(0 < r["flagged_fraction"] < 1 for r in crossing)


@pytest.mark.requires_gpu
def test_the_speed_rows_compare_every_method_to_direct_in_the_same_run(rows):
    speed = [r for r in rows if r["sweep"] == "speed"]
    frames = {(r["span_length"], r["spans"]) for r in speed}
    assert len(frames) == len(study.SUITES["smoke"].speed_frames)
    for frame in frames:
        here = [r for r in speed if (r["span_length"], r["spans"]) == frame]
        assert {r["method"] for r in here} == set(METHODS) | {"hardware"}
        direct = next(r for r in here if r["method"] == "direct")
        assert direct["scalar_ratio"] == direct["simd_ratio"] == 1.0
        # the software adapter's wall-net time of a smoke frame can be all overhead on a busy machine (clamped to 0):
        # then no method has a GPU ratio to direct, and the row says so
        assert direct["gpu_ratio"] == 1.0 if direct["gpu_ms"] > 0 else math.isnan(direct["gpu_ratio"])
        methods = [r for r in here if r["method"] != "hardware"]
        assert all(r["scalar_ns"] > 0 and r["simd_ns"] > 0 and r["scalar_spread"] >= 0 for r in methods)
        assert all(r["simd_vectorised"] == "scalar" or r["simd_vectorised"].startswith(("loop x", "slp x"))
                   for r in methods)
        assert all(r["numpy_ms"] > 0 for r in methods)
        # wall-net times of passes faster than the submit overhead's noise can come out as 0
        on_gpu = [r for r in here if r["method"] == "hardware" or METHODS[r["method"]].on_gpu]
        assert all(r["gpu_ms"] >= 0 and r["timer"] in ("timestamp", "wall-net") for r in on_gpu)
        assert all(r["gpu_ms"] is None for r in here if r not in on_gpu)
        assert direct["gpu_ms"] > 0
    tiles = [r for r in rows if r["sweep"] == "speed_tile"]
    assert {r["method"] for r in tiles} == set(METHODS)
    assert {r["span_length"] for r in tiles} == {study.SUITES["smoke"].tile_timing}
    assert next(r for r in tiles if r["method"] == "direct")["scalar_ratio"] == 1.0
    assert all(r["scalar_ns"] > 0 and r["simd_ns"] > 0 and r["gpu_ms"] is None for r in tiles)


@pytest.mark.requires_gpu
def test_the_report_answers_the_issue_with_numbers(smoke):
    text = (smoke / "report.md").read_text(encoding="utf-8")
    assert text.startswith("# Perspective-correct texturing: speed against float error (Romanyuk & Dudnyk)\n\n"
                           f"- command: `wgpuviewer perspective --out {smoke} --suite smoke --quiet`\n- adapter: **")
    assert "- CPU: " in text.split("## Recommendation")[0]
    recommendation = text.split("## Recommendation")[1].split("## Answers")[0]
    regimes = [line for line in recommendation.splitlines() if line.startswith("| ") and "px" in line]
    assert len(regimes) >= 5 and all("×" in line or "none within" in line for line in regimes)
    assert "Short spans" in recommendation and "Large coordinates" in recommendation
    answers = text.split("## Answers")[1].split("## Checks")[0]
    for topic in ("Fastest as a compiled scalar loop", "Fastest as a compiled SIMD build", "Fastest on the ",
                  "Float32 incremental drift", "k-parallel and two-ended", "Mitigations", "Approximations",
                  "Large coordinates"):
        line = next(line for line in answers.splitlines() if topic in line)
        assert any(c.isdigit() for c in line) and " px" in line, topic
    assert "1080p" in answers and "4K" in answers
    assert "0 ulp" in text or "software" not in text
    if "**software**" in text:  # the software adapter's times are labelled as such wherever they appear
        assert "Fastest on the software GPU adapter (its kernels run on the CPU)" in answers
        assert "## Timing on the software GPU adapter (its kernels run on the CPU), and numpy's" in text
        assert "GPU ×" not in text and "software GPU adapter × direct" in text


@pytest.mark.requires_gpu
def test_the_relief_tieback_covers_every_technique_magnitude_and_variant(smoke):
    relief = study.TIEBACK_TABLE.read(smoke / "tieback.csv")
    suite = study.SUITES["smoke"]
    assert len(relief) == len(suite.relief_techniques) * len(suite.relief_magnitudes) * len(tieback.VARIANTS)
    big = [r for r in relief if r["magnitude_uv"] == max(suite.relief_magnitudes)]
    small = [r for r in relief if r["magnitude_uv"] == 0]
    # at 1e7 UV units float32's spacing is a whole tile: every technique is lost; at 0 all are sub-texel
    assert all(r["p99_err"] > 10 for r in big) and all(r["p99_err"] < 1 for r in small)
    # the search runs on the entry point's fraction: what magnitude adds is the entry point's quantisation
    at_zero = {r["technique"]: r["p99_err"] for r in small}
    assert all(r["p99_err"] <= at_zero[r["technique"]] + 1.5 * r["input_spacing_texels"] for r in relief)


def test_without_numba_the_command_fails_with_one_line_before_any_work(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "numba", None)  # import numba raises ImportError
    out = tmp_path / "out"
    assert cli.main(["perspective", "--out", str(out), "--suite", "smoke"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "numba" in err and "pip install" in err
    assert not out.exists()


def test_bad_command_lines_fail_with_one_line(tmp_path, capsys):
    existing = tmp_path / "file"
    existing.write_text("x")
    assert cli.main(["perspective", "--out", str(existing), "--suite", "smoke"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--out" in err and "not a folder" in err
    assert cli.main(["perspective", "--out", str(existing / "sub"), "--suite", "smoke"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "cannot write there" in err
    for argv in (["perspective", "--out", str(tmp_path), "--suite", "huge"],
                 ["perspective", "--suite", "smoke"]):  # an unknown suite; --out missing
        assert cli.main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and "--help" in err


#: ``wgpuviewer perspective`` whose measurement stops in its first plot's write (the real study takes ~20 s on
#: the software adapter before it writes anything).
STOPPED_MID_WRITE = textwrap.dedent("""
    import sys, time
    from wgpuviewer import cli
    from wgpuviewer.core.io import atomic_open
    from wgpuviewer.lab.studies.perspective import run as study

    def run(*args, **kwargs):
        with atomic_open(sys.argv[1] + "/error_along_span.png") as f:
            f.write(b"partial")
            f.flush()
            print("writing", flush=True)
            time.sleep(60)

    study.run = run
    sys.exit(cli.main(["perspective", "--out", sys.argv[1], "--suite", "smoke", "--quiet"]))
""")


def test_sigterm_mid_write_leaves_no_temp(tmp_path):
    proc = subprocess.Popen([sys.executable, "-c", STOPPED_MID_WRITE, str(tmp_path)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "writing"
        assert [p.name for p in tmp_path.glob(".error_along_span.png.*.tmp")]
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 143 and err.strip() == "wgpuviewer: terminated", err
    assert list(tmp_path.iterdir()) == []
