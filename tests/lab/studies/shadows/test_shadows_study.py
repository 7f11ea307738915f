"""The shadow study: its options are checked before anything runs, and the smoke suite runs end to end."""

from __future__ import annotations

import pytest

from wgpuviewer.cli import main
from wgpuviewer.lab.harness.study import discover
from wgpuviewer.lab.studies.shadows.run import RESULTS
from wgpuviewer.relief.accuracy import shadowing_techniques


def test_the_study_is_a_command_and_casts_shadows_only_with_searching_techniques():
    assert "shadows" in [s.name for s in discover()]
    names = shadowing_techniques()
    assert "parallax" not in names and "basic" not in names and {"pom", "maxmip", "quadmax"} <= set(names)


@pytest.mark.parametrize("option", ["--elevations=0", "--elevations=91", "--techniques=parallax",
                                    "--heightmaps=nope"])
def test_bad_options_are_one_line_and_exit_2(tmp_path, capsys, option):
    assert main(["shadows", "--out", str(tmp_path / "out"), "--suite", "smoke", option]) == 2
    assert not (tmp_path / "out").exists()
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


@pytest.mark.requires_gpu
def test_smoke_suite_end_to_end(tmp_path):
    out = tmp_path / "out"
    assert main(["shadows", "--out", str(out), "--suite", "smoke", "--quiet"]) == 0
    rows = RESULTS.read(out / "results.csv")
    assert len(rows) == 2 * 2 * 2  # maps x techniques x elevations
    assert all(0.0 < r["ref_lit"] < 1.0 for r in rows if r["elevation"] == 30.0)  # shadows to get right
    for row in rows:
        assert row["hard_fetches"] > 0 and row["hard_fetches_simd"] >= row["hard_fetches"]
    exact = [r for r in rows if r["technique"] == "maxmip"]
    assert max(r["hard_wrong"] for r in exact) <= 0.01  # the exact tracer: only boundary rays
    assert "| `maxmip` |" in (out / "report.md").read_text() and (out / "shadows.png").exists()
