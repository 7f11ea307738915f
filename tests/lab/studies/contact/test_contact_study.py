"""The contact study: a command, and its smoke suite end to end (results.csv, report.md, the docs block's tables)."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.cli import main
from wgpuviewer.lab.harness.study import discover
from wgpuviewer.lab.studies.contact.report import cell_counts, cost_beaten, pairs, relief_frontier_at, report
from wgpuviewer.lab.studies.contact.run import RESULTS, settings


def test_the_study_is_a_command_and_its_pairs_share_the_fetch_bound():
    from wgpuviewer.core.params import resolve_params
    from wgpuviewer.techniques import TECHNIQUES

    assert "contact" in [s.name for s in discover()]
    for n, extra in ((1, 1), (8, 2), (16, 6)):
        bounds = {t: TECHNIQUES[t].fetch_bound(resolve_params(TECHNIQUES[t], settings(t, n, extra)))
                  for t in ("relief", "contact")}
        assert bounds == {"relief": n + 1 + extra, "contact": n + 1 + extra}


def test_the_tables_of_synthetic_rows():
    rows = [{"heightmap": "m", "angle": 45.0, "technique": t, "linear_steps": 8, "extra": 2, "fetch_bound": 11,
             "err_p50": 0.0, "err_p95": p95, "fetches_mean": 9.0, "fetches_simd": simd, "capped": 0.0}
            for t, p95, simd in (("relief", 0.1, 10.0), ("contact", 0.2, 9.0))]
    assert list(pairs(rows)) == [("m", 45.0, 8, 2)]
    assert cell_counts(rows) == (0, 0, 1)  # relief lower
    assert cost_beaten(rows) == (0, 0, [])  # contact is cheaper than every relief setting: nothing to compare
    more = rows + [{**rows[0], "extra": 1, "err_p95": 1.0, "fetches_simd": 8.0}]  # relief's envelope: 8 -> 10 fetches
    assert relief_frontier_at([r for r in more if r["technique"] == "relief"], 9.0) == pytest.approx(
        np.sqrt(1.001 * 0.101) - 1e-3)
    assert cost_beaten(more) == (1, 1, [("m", 45.0)])  # 0.2 below the envelope's 0.32 at 9 fetches
    assert "| m | 1.99 |" in "\n".join(report(rows))  # (0.2 + FLOOR) / (0.1 + FLOOR)


@pytest.mark.requires_gpu
def test_smoke_suite_end_to_end(tmp_path):
    out = tmp_path / "out"
    assert main(["contact", "--out", str(out), "--suite", "smoke", "--quiet"]) == 0
    rows = RESULTS.read(out / "results.csv")
    assert len(rows) == 2 * 2 * 2  # maps x angles x techniques (one pair)
    for row in rows:
        assert row["fetches_mean"] <= row["fetch_bound"] and row["fetches_simd"] >= row["fetches_mean"] - 1e-9
        assert 0 <= row["err_p50"] <= row["err_p95"]
    text = (out / "report.md").read_text()
    assert "contact p95 / relief p95" in text and "| bumps |" in text
