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
from wgpuviewer.relief.renderer import Renderer  # noqa: F401 - imports wgpu before the log fixture touches its logger
from wgpuviewer.studies.perspective import run as study
from wgpuviewer.studies.perspective.methods import METHODS, PARALLEL_THREADS
from wgpuviewer.studies.perspective.report import PLOTS

REQUIRED_METHODS = {"direct", "span", "incremental", *(f"parallel_{k}" for k in PARALLEL_THREADS), "two_ended",
                    "subdivided_8", "subdivided_16", "hardware", "reanchor_64", "kahan", "double_single",
                    "fixed16_16"}


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
    assert {r["sweep"] for r in rows} == {"span_length", "tilt", "magnitude", "speed"}
    suite = study.SUITES["smoke"]
    assert {r["span_length"] for r in rows if r["sweep"] == "span_length"} == set(suite.span_lengths)
    for r in rows:
        if r["tilt_deg"] < 90:
            assert math.isfinite(r["max_err"]) and r["flagged_fraction"] == 0, r


@pytest.mark.requires_gpu
def test_the_run_checks_kernels_against_their_twins_and_flags_every_undefined_texel(gpu, rows):
    checked = [r for r in rows if r["gpu_max_ulp"] is not None]
    assert {r["method"] for r in checked} == set(METHODS)
    if gpu.software:
        assert all(r["gpu_max_ulp"] == 0 and r["gpu_flag_mismatch"] == 0 for r in checked)
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
        assert next(r for r in here if r["method"] == "direct")["gpu_ratio"] == 1.0
        # wall-net times of passes faster than the submit overhead's noise can come out as 0
        assert all(r["gpu_ms"] >= 0 and r["timer"] in ("timestamp", "wall-net") for r in here)
        assert next(r for r in here if r["method"] == "direct")["gpu_ms"] > 0
        assert all(r["cpu_ms"] > 0 for r in here if r["method"] != "hardware")


@pytest.mark.requires_gpu
def test_the_report_answers_the_issue_with_numbers(smoke):
    text = (smoke / "report.md").read_text(encoding="utf-8")
    assert text.startswith("# Perspective-correct texturing: speed against float error (Romanyuk & Dudnyk)\n\n"
                           f"- command: `wgpuviewer perspective --out {smoke} --suite smoke --quiet`\n- adapter: **")
    answers = text.split("## Answers")[1].split("## Checks")[0]
    for topic in ("Fastest on the GPU", "Fastest on the CPU", "Float32 incremental drift", "k-parallel and two-ended",
                  "Mitigations", "Large coordinates"):
        line = next(line for line in answers.splitlines() if topic in line)
        assert any(c.isdigit() for c in line), topic
    assert "1080p" in answers and "4K" in answers
    assert "0 ulp" in text or "software" not in text


@pytest.mark.requires_gpu
def test_the_relief_tieback_covers_every_technique_magnitude_and_variant(smoke):
    relief = study.TIEBACK_TABLE.read(smoke / "tieback.csv")
    suite = study.SUITES["smoke"]
    assert len(relief) == len(suite.relief_techniques) * len(suite.relief_magnitudes) * 2
    big = [r for r in relief if r["magnitude_uv"] == max(suite.relief_magnitudes)]
    small = [r for r in relief if r["magnitude_uv"] == 0]
    # at 1e7 UV units float32's spacing is a whole tile: every technique is lost; at 0 all are sub-texel
    assert all(r["p99_err"] > 10 for r in big) and all(r["p99_err"] < 1 for r in small)


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
    from wgpuviewer.studies.perspective import run as study

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
