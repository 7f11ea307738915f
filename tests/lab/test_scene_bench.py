"""The scene benchmark: the footprint and the hit error in pixels on a known screen-to-uv map, its options checked
before anything runs, its configurations on every checkout, and the smoke suite end to end on a tiny scene (the
exact tracer's own row is exact, the techniques' errors are small and ordered by their fetches)."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.cli import main
from wgpuviewer.lab.harness.study import discover
from wgpuviewer.lab.studies.scene_bench import configs, measure, run, scenes

TINY_SCENE = """
[scene]
techniques = ["pom"]
[camera]
position = [0.0, 0.8, 1.6]
target = [0.0, 0.0, 0.0]
[materials.bumps]
albedo = { builtin = "bumps", size = [64, 64] }
height = { builtin = "bumps", size = [64, 64] }
height_scale = 0.08
[[objects]]
type = "plane"
material = "bumps"
size = [2.0, 2.0]
"""


def test_the_footprint_inverts_a_known_screen_to_uv_map_up_to_the_edges():
    h, w = 12, 16
    jacobian = np.array([[0.02, 0.005], [-0.004, 0.03]])  # columns: d uv / dx, d uv / dy
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    uv = np.einsum("ij,hwj->hwi", jacobian, np.stack([x, y], -1)) + 0.3
    covered = np.ones((h, w), bool)
    covered[:, 10:] = False  # an edge: the pixels beside it use the difference on their own side
    uv[~covered] = 50.0  # another surface's uv there must not leak into the footprint
    inverse, ok = measure.inverse_footprint(uv, covered)
    assert ok.sum() == covered.sum()
    np.testing.assert_allclose(inverse[ok], np.broadcast_to(np.linalg.inv(jacobian), (ok.sum(), 2, 2)), atol=1e-9)
    shift = jacobian @ np.array([1.5, -2.0])  # a hit 1.5 pixels right and 2 up: 2.5 pixels off
    errors = measure.pixel_errors(uv + shift, uv, inverse, ok)
    np.testing.assert_allclose(errors, 2.5, rtol=1e-9)
    lone = np.zeros((h, w), bool)
    lone[5, 5] = True  # no covered neighbour: no footprint
    assert not measure.inverse_footprint(uv, lone)[1].any()


def test_psnr_and_fetch_statistics():
    color = np.zeros((4, 8, 3), np.uint8)
    other = color.copy()
    other[0, 0] = 255
    mask = np.ones((4, 8), bool)
    assert measure.psnr_db(color, color, mask) == float("inf")
    assert measure.psnr_db(color, other, mask) == pytest.approx(10 * np.log10(32))
    data = np.zeros((4, 8, 4), np.float32)
    data[0, 0, 3] = 7.0
    data[3, 7, 3] = -4.0  # capped after 3 fetches
    stats = measure.fetch_stats(data, mask)
    assert stats["fetches_mean"] == pytest.approx(10 / 32) and stats["capped"] == pytest.approx(1 / 32)
    assert stats["fetches_simd"] == 7.0  # one 8x4 tile: its slowest lane


def test_configurations_run_on_every_checkout():
    found = configs.configs((("pom", {"layers": 8}), ("pom", {"layers": 8}), ("pom", {"no_such": 1}),
                         ("no_such_technique", {}), ("relief", {})))
    assert [name for name, _ in found] == ["pom", "relief"]
    assert found[0][1]["layers"] == 8 and "binary_steps" in found[1][1]
    assert "scene-bench" in [s.name for s in discover()]
    cameras = scenes.views(scenes.load("default", None).camera)
    assert list(cameras) == list(scenes.VIEWS)
    assert cameras["grazing"].target[1] == 0.0 and cameras["grazing"].position[1] > 0.0


@pytest.mark.parametrize("args", [["no_such_scene"], ["--size", "64"], ["--size", "0x10"]])
def test_bad_options_are_one_line_and_exit_2(tmp_path, capsys, args):
    assert main(["scene-bench", "--out", str(tmp_path / "out"), "--suite", "smoke", *args]) == 2
    assert not (tmp_path / "out").exists()
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


@pytest.fixture(scope="module")
def smoke(tmp_path_factory):
    folder = tmp_path_factory.mktemp("scene-bench")
    (folder / "tiny.toml").write_text(TINY_SCENE)
    out = folder / "out"
    assert main(["scene-bench", str(folder / "tiny.toml"), "--suite", "smoke", "--out", str(out), "--quiet"]) == 0
    return out


@pytest.mark.requires_gpu
def test_smoke_suite_end_to_end(smoke):
    rows = {r["technique"]: r for r in run.RESULTS.read(smoke / "results.csv")}
    assert list(rows) == ["basic", "maxmip", "pom", "relief"]
    exact = rows["maxmip"]
    assert exact["px_err_p95"] == 0.0 and exact["flip_mean"] == 0.0 and exact["capped"] == 0.0
    assert rows["basic"]["ratio_to_basic"] == 1.0 and rows["basic"]["fetches_simd"] == 0.0
    for name in ("pom", "relief"):
        row = rows[name]
        assert row["pixels"] > 1000 and row["fetches_simd"] >= row["fetches_mean"] > 0
        assert row["px_err_p50"] < 0.25 and 0.0 < row["flip_mean"] < rows["basic"]["flip_mean"]
        assert row["psnr_db"] > rows["basic"]["psnr_db"]
    assert rows["relief"]["px_err_p50"] <= rows["pom"]["px_err_p50"]  # 16 linear and 6 binary steps against 8 layers
    report = (smoke / "report.md").read_text()
    assert report.startswith("# Scene benchmark") and "| `relief linear_steps=16 binary_steps=6` |" in report
    assert (smoke / "pareto.png").exists() and (smoke / "worst_pixels.png").exists()
