"""The filtering study's per-relief verdict: wins and losses counted beyond the reference's error, the bootstrap
interval of the mean difference, the verdict's words, the row-ends comparison, and runs merged without mixing cases."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.lab.studies.filtering import byrelief
from wgpuviewer.lab.studies.filtering.aggregate import label

VIS, PLAIN = label("ewa_vis", "analytic"), label("ewa", "analytic")
ROWS_END, FULL = label("ewa_vis_rows", "displaced"), label("ewa_vis", "displaced")


def row(case, relief, albedo, name, psnr, uncertainty=0.1, time=1.0, fetches=100.0):
    return {"case": case, "relief": relief, "albedo": albedo, "label": name, "psnr": psnr, "role": "rank",
            "void": "", "psnr_uncertainty": uncertainty, "time_ratio": time, "depth_fetches_per_pixel": fetches}


def test_the_bootstrap_interval_holds_the_mean_and_narrows_to_a_constant():
    assert byrelief.bootstrap_mean([2.5] * 7) == (2.5, 2.5)
    values = list(np.random.default_rng(1).normal(1.0, 2.0, 40))
    low, high = byrelief.bootstrap_mean(values)
    assert low < np.mean(values) < high
    assert high - low < 2.0 * 2.0  # about 4 standard errors (2 / sqrt(40) each), far below the spread itself
    assert byrelief.bootstrap_mean(values) == (low, high)  # seeded: the same from the same results
    assert all(np.isnan(byrelief.bootstrap_mean([])))


@pytest.mark.parametrize(("better", "worse", "low", "high", "words"), [
    (5, 1, 0.2, 3.0, "holds"), (1, 5, -3.0, -0.2, "fails"), (3, 3, -1.0, 2.0, "mixed"),
    (5, 1, -0.1, 3.0, "mixed"), (0, 0, -0.3, -0.1, "no difference")])
def test_the_verdict_needs_both_the_interval_and_the_case_count(better, worse, low, high, words):
    assert byrelief.verdict(better, worse, low, high) == words


def test_verdict_rows_count_signs_per_relief_and_albedo_class():
    rows = []
    for k, (vis, plain) in enumerate([(30.0, 25.0), (28.0, 27.95), (20.0, 24.0)]):  # win, tie, loss
        rows += [row(f"b{k}", "bricks", "own", VIS, vis), row(f"b{k}", "bricks", "own", PLAIN, plain)]
    rows += [row("s0", "step", "checker", VIS, 20.0), row("s0", "step", "checker", PLAIN, 21.0)]
    found = {(v["relief"], v["albedos"]): v for v in byrelief.verdict_rows(rows)}
    bricks = found[("bricks", "follows")]
    assert (bricks["cases"], bricks["better"], bricks["worse"]) == (3, 1, 1)
    assert bricks["mean"] == pytest.approx((5.0 + 0.05 - 4.0) / 3)
    assert (bricks["min"], bricks["max"]) == pytest.approx((-4.0, 5.0))
    assert bricks["low"] <= bricks["mean"] <= bricks["high"]
    assert found[("step", "independent")]["worse"] == 1
    assert "| bricks | follows | `ewa_vis (analytic)` | 3 | 1 / 1 |" in "\n".join(byrelief.verdict_table(rows))


def test_row_ends_reports_time_and_fetches_against_the_full_method():
    rows = [row("a", "bricks", "own", FULL, 30.0, time=10.0, fetches=100.0),
            row("a", "bricks", "own", ROWS_END, 30.0, time=11.0, fetches=95.0),
            row("b", "step", "own", FULL, 30.0, time=10.0, fetches=200.0),
            row("b", "step", "own", ROWS_END, 30.5, time=9.0, fetches=190.0)]
    (found,) = byrelief.row_ends(rows)
    assert (found["cases"], found["slower"]) == (2, 1)
    assert found["time"][0] == pytest.approx(-0.1) and found["time"][2] == pytest.approx(0.1)
    assert found["fetches"][0] == pytest.approx(0.05) and found["fetches"][2] == pytest.approx(0.05)
    assert found["psnr"] == pytest.approx((0.0, 0.5))
    assert "slower in 1 of 2 cases" in byrelief.row_ends_lines(rows)[0]


def test_merged_runs_never_mix_a_case():
    one = [row("c", "bricks", "own", VIS, 30.0), row("c", "bricks", "own", PLAIN, 20.0)]
    two = [row("c", "bricks", "own", VIS, 20.0), row("c", "bricks", "own", PLAIN, 30.0)]
    (found,) = byrelief.verdict_rows(byrelief.merged({"one": one, "two": two}))
    assert (found["cases"], found["better"], found["worse"]) == (2, 1, 1)
