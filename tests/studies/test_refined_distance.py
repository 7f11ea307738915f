"""The refined-distance study: its numpy twin of the distance tracer takes the GPU tracer's steps (same fetch
counts, same hits), so the variants it measures are measured as the renderer would; the smoke suite end to end."""

from __future__ import annotations

import numpy as np
import pytest

from maptools.cache import cached_generate
from wgpuviewer.bench.run import REAL_MAPS
from wgpuviewer.relief.accuracy import random_rays
from wgpuviewer.relief.maps import DISTANCE_SLICES, depth_range
from wgpuviewer.relief.probe import probe
from wgpuviewer.relief.reference import exact_hit
from wgpuviewer.relief.techniques import REFINED_BANDS, REFINED_MAX_ANGLE, REFINED_SECTORS
from wgpuviewer.studies.refined_distance.baseline import plain_before
from wgpuviewer.studies.refined_distance.run import SUITES, VARIANTS, run
from wgpuviewer.studies.refined_distance.tracer import trace
from wgpuviewer.textures import BUILTINS, builtin_height


@pytest.mark.parametrize("name", ["bricks", "wall"])
def test_twin_takes_the_gpu_tracers_steps(gpu, name):
    h = builtin_height(name, (48, 48)).astype(np.float64)
    depth = 1.0 - h
    plain = cached_generate("distance", h, backend="auto", slices=DISTANCE_SLICES, height_scale=0.05)
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
    rows = run("smoke", tmp_path, progress=False, command="wgpuviewer refined-distance --suite smoke")
    suite = SUITES["smoke"]
    twins = [r for r in rows if r["tracer"] == "numpy twin"]
    assert len(twins) == len(suite.heightmaps) * len(suite.angles) * len(VARIANTS)
    gpu_rows = [r for r in rows if r["tracer"] != "numpy twin"]
    assert {r["variant"] for r in gpu_rows} == {v.name for v in VARIANTS if v.technique}
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
    assert "## bricks" in text and "product vs before" in text
    assert (tmp_path / "results.csv").read_text().startswith("heightmap,size,angle,variant")
    assert (tmp_path / "fetches_vs_angle.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


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
                                               "expected some of " + ", ".join((*BUILTINS, *REAL_MAPS)))
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
