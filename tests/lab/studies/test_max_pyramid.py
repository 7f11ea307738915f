"""The max-pyramid study: its twin of the maxmip walk is exact in float64 and counts its steps consistently; equal
error and equal cost are interpolated on the cost-error curve; the smoke suite end to end (the files and their
columns, the twin against the GPU probe ray by ray, the claim table's cells recomputed from the rows)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from wgpuviewer.lab.studies.max_pyramid.compare import cost_at_error, error_at_cost
from wgpuviewer.lab.studies.max_pyramid.figures import PAPER_FIG3, example_ray
from wgpuviewer.lab.studies.max_pyramid.reliefs import CLASSES, dem, plates
from wgpuviewer.lab.studies.max_pyramid.run import SUITES, run
from wgpuviewer.lab.studies.max_pyramid.tables import COMPETITORS, LEVELS_TABLE, SWEEP_TABLE, TABLE
from wgpuviewer.lab.studies.max_pyramid.twin import levels, pyramid, walk
from wgpuviewer.relief.accuracy import random_rays
from wgpuviewer.relief.reference import exact_hit
from wgpuviewer.textures import builtin_height


def test_twin_finds_the_exact_hit_and_counts_every_step():
    depth = 1.0 - builtin_height("bumps", (24, 24)).astype(np.float64)
    for angle in (0.0, 60.0, 85.0):
        uv, v = random_rays(300, angle, seed=3)
        w = walk(depth, uv, v, 0.05, float(depth.min()))
        ref = exact_hit(depth, uv.astype(np.float32), v.astype(np.float32), 0.05)  # the inputs the twin traces
        assert ref.valid.all() and not w.capped.any()
        assert np.allclose(w.t, ref.t, atol=1e-9) and np.allclose(w.uv, ref.uv, atol=1e-9)
        stats = levels(w)
        assert math.isclose(sum(s.steps_per_ray for s in stats) * len(uv), w.fetches.sum())
        assert stats[-1].steps_per_ray >= 1.0 and all(s.most_in_parent <= 4 for s in stats[:-1])


def test_the_papers_pyramid_and_its_example_ray():
    atlas, rows = pyramid(1.0 - PAPER_FIG3)
    assert list(rows) == [0, 8, 12, 14] and atlas[rows[-1], 0] == np.float32(0.9)  # the top: the global max
    uv, v, w, ray = example_ray()
    assert set(w.step_level[w.step_ray == ray]) == {0, 1, 2, 3}  # the example visits every level


def test_equal_error_and_equal_cost_interpolate_in_log_log():
    curve = [(c, 10.0 / c) for c in (2.0, 4.0, 8.0, 16.0)]  # error = 10 / cost
    cost, flag = cost_at_error(curve, 1.0)
    assert flag == "" and cost == pytest.approx(10.0)
    assert cost_at_error(curve, 100.0) == (2.0, "<=") and cost_at_error(curve, 0.1) == (16.0, ">")
    error, flag = error_at_cost(curve, 5.0)
    assert flag == "" and error == pytest.approx(2.0)
    assert error_at_cost(curve, 1.0) == (5.0, ">=") and error_at_cost(curve, 32.0) == (0.625, "<=")


def test_generated_reliefs():
    p = plates(64)
    assert p.shape == (64, 64) and p.max() == 1.0 and p.min() == 0.0 and (p == p.max()).mean() > 0.1
    pytest.importorskip("cv2")
    d = dem(32)
    assert d.shape == (32, 32) and d.min() == 0.0 and d.max() == 1.0


@pytest.fixture(scope="module")
def smoke(tmp_path_factory, gpu):
    out = tmp_path_factory.mktemp("max_pyramid")
    rows, level_rows, sweep = run("smoke", out, progress=False, command="wgpuviewer max-pyramid --suite smoke",
                                   pictures=False)
    return out, rows, level_rows, sweep


def test_smoke_files_and_columns(smoke):
    out, rows, level_rows, sweep = smoke
    suite = SUITES["smoke"]
    read = TABLE.read(out / "results.csv")
    assert [(r["heightmap"], r["angle"], r["tracer"]) for r in read] == [(r["heightmap"], r["angle"], r["tracer"])
                                                                         for r in rows]
    assert len(rows) == len(suite.heightmaps) * len(suite.angles) * 2
    assert "level" in LEVELS_TABLE.names and {r["level"] for r in LEVELS_TABLE.read(out / "levels.csv")} == set(
        range(6))  # a 32x32 map: levels 0 to 5
    assert len(SWEEP_TABLE.read(out / "sweep.csv")) == len(rows) // 2 * (len(COMPETITORS) * len(suite.layers) + 2)
    for r in rows:
        assert r["fetches_simd"] >= r["fetches_mean"] >= 1 and r["capped"] == 0
        assert r["relief_class"] == CLASSES[r["heightmap"]]
    text = (out / "report.md").read_text()
    assert text.startswith("# ") and "- command: `wgpuviewer max-pyramid --suite smoke`" in text


def test_smoke_twin_equals_the_gpu_probe(smoke):
    _, rows, _, _ = smoke
    walks = [r for r in rows if r["tracer"] == "maxmip"]
    assert walks and all(r["twin_same_fetches"] >= 0.995 and r["twin_hit_diff"] < 1e-3 for r in walks)
    for r in walks:  # the twin's steps per level add up to the probe's fetches per ray (the twin's = the probe's)
        assert sum(r[f"steps_l{m}"] or 0.0 for m in range(9)) == pytest.approx(r["fetches_mean"], rel=0.01)
        assert r["error_max"] < 0.01  # exact: the paper's "without loss of accuracy" holds for the walk


def test_smoke_claim_cells_come_from_the_rows(smoke):
    out, rows, _, _ = smoke
    text = (out / "report.md").read_text()
    for cls in sorted({r["relief_class"] for r in rows}):
        mine = [r for r in rows if r["tracer"] == "maxmip" and r["relief_class"] == cls]
        wins = sum(r["fetches_simd"] < min(r[f"{c}_simd_p95"] for c in COMPETITORS) for r in mine)
        maps = ", ".join(sorted({r["heightmap"] for r in mine}))
        assert f"| maxmip | {cls} | {maps} | {len(mine)} | {wins} of {len(mine)} |" in text
