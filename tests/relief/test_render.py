"""Offscreen rendering: golden images per technique, determinism, modes, lazy resources."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from wgpuviewer.relief.output import mode_data, mode_picture
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.relief.targets import OFFSCREEN_FORMATS
from wgpuviewer.scene import default_scene_path, load_scene
from wgpuviewer.techniques import TECHNIQUES

ROOT = Path(__file__).resolve().parents[2]
GOLDEN = Path(__file__).parent / "golden"
FAILURES = Path(__file__).parent / "_failures"
GOLDEN_SIZE = (192, 108)
# Golden images only hold for the adapter family they were made on (rasterisation and filtering
# precision differ between GPUs): the family is the first word of the adapter name + the backend.
GOLDEN_ADAPTER = GOLDEN / "adapter.txt"
MAX_MEAN_DIFF = 0.5  # mean absolute difference, 8-bit levels
MAX_BAD_FRACTION = 0.002  # fraction of pixels more than 16 levels off
OFFSCREEN = "+".join(OFFSCREEN_FORMATS)  # the targets in a pipeline's name


def adapter_family(summary: str) -> str:
    return f"{summary.split()[0]} {summary.rsplit(' via ', 1)[-1]}"


@pytest.fixture(scope="module")
def default_renderer(gpu):
    return Renderer(load_scene(GOLDEN / "scene.toml"), gpu)


@pytest.mark.parametrize("technique", list(TECHNIQUES))
def test_golden_image(default_renderer, adapter, request, technique):
    image = default_renderer.render(technique, GOLDEN_SIZE).color[:, :, :3]
    path = GOLDEN / f"{technique}.png"
    if request.config.getoption("--regen-golden"):
        GOLDEN.mkdir(exist_ok=True)
        cv2.imwrite(str(path), cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
        GOLDEN_ADAPTER.write_text(adapter_family(adapter) + "\n")
        return
    if not path.exists():
        pytest.fail(f"no golden image {path.name}: run pytest --regen-golden on the reference adapter")
    family = GOLDEN_ADAPTER.read_text().strip()
    if adapter_family(adapter) != family:
        pytest.skip(f"golden images are for {family}, this adapter is {adapter}")
    golden = cv2.cvtColor(cv2.imread(str(path)), cv2.COLOR_BGR2RGB)
    diff = np.abs(image.astype(np.int16) - golden.astype(np.int16))
    mean, bad = diff.mean(), (diff.max(axis=2) > 16).mean()
    if mean > MAX_MEAN_DIFF or bad > MAX_BAD_FRACTION:
        FAILURES.mkdir(exist_ok=True)
        cv2.imwrite(str(FAILURES / f"{technique}_got.png"), cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
        cv2.imwrite(str(FAILURES / f"{technique}_diff.png"), np.clip(diff * 8, 0, 255).astype(np.uint8))
        pytest.fail(f"{technique}: mean diff {mean:.3f}, {bad:.2%} pixels off; see {FAILURES}")


def test_techniques_differ(default_renderer):
    """Each technique changes the picture or its cost (a technique silently falling back to another would not).
    Accurate techniques converge to the same picture (maxmip and distance are both exact), so a pair may also
    differ in the fetches per pixel instead."""
    renders = {t: default_renderer.render(t, GOLDEN_SIZE) for t in TECHNIQUES}
    images = {t: r.color[:, :, :3].astype(np.int16) for t, r in renders.items()}
    costs = {t: np.nan_to_num(mode_data(r, "cost")) for t, r in renders.items()}
    names = list(images)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            if TECHNIQUES[a].wgsl_file == TECHNIQUES[b].wgsl_file:
                # distance / distance_refined: one tracer, two maps, one exact picture; the refined map takes fewer steps
                assert (costs[a] != costs[b]).any(), (a, b)
                continue
            assert np.abs(images[a] - images[b]).mean() > 0.3 or (costs[a] != costs[b]).any(), (a, b)


def test_same_input_same_bytes(gpu):
    scene = load_scene(default_scene_path())
    first = Renderer(scene, gpu).render("pom", (96, 64))
    second = Renderer(scene, gpu).render("pom", (96, 64))
    assert first.color.tobytes() == second.color.tobytes()
    assert first.data.tobytes() == second.data.tobytes()


def test_modes_hold_raw_trace_data(default_renderer):
    image = default_renderer.render("pom", (128, 72))
    covered = image.covered
    assert 0.3 < covered.mean() < 1.0  # the plane and box cover part of the frame, the sky the rest
    uv, depth, cost = (mode_data(image, m) for m in ("uv", "layer_depth", "cost"))
    assert uv.shape == (72, 128, 2) and depth.shape == cost.shape == (72, 128)
    assert np.isnan(depth[~covered]).all() and np.isfinite(depth[covered]).all()
    assert ((depth[covered] >= 0) & (depth[covered] <= 1)).all()
    layers = default_renderer.config("pom").values["layers"]
    assert cost[covered].min() >= 1 and cost[covered].max() <= layers + 1
    assert cost[covered].mean() > 2  # POM really marches
    basic = mode_data(default_renderer.render("basic", (128, 72)), "cost")
    assert np.nanmax(basic) == 0
    for mode in ("color", "uv", "depth", "layer_depth", "cost"):
        picture = mode_picture(image, mode)
        assert picture.shape == (72, 128, 3) and picture.dtype == np.uint8


def test_only_what_the_scene_needs(gpu):
    """A normal-mapping scene builds no height-derived GPU resource and compiles one pipeline."""
    scene = load_scene(ROOT / "scenes" / "normal_only.toml")
    renderer = Renderer(scene, gpu)
    assert renderer.created == []  # nothing before the first frame
    renderer.render("normal", (64, 64))
    assert not [c for c in renderer.created if c.endswith(".depth")]
    assert [c for c in renderer.created if c.startswith("pipeline:")] == [f"pipeline:normal:{OFFSCREEN}"]
    textures = sorted(c for c in renderer.created if c.startswith("texture:"))
    assert textures == ["texture:bricks.albedo", "texture:bricks.normal"]


def test_resources_follow_the_selected_technique(gpu):
    renderer = Renderer(load_scene(default_scene_path()), gpu)
    renderer.render("basic", (32, 32))
    assert all(c.endswith(".albedo") for c in renderer.created if c.startswith("texture:"))
    renderer.render("pom", (32, 32))
    assert {"texture:bricks.depth", "texture:bumps.depth"} <= set(renderer.created)
    before = list(renderer.created)
    renderer.render("pom", (32, 32))
    renderer.render("steep", (32, 32))
    assert renderer.created[: len(before)] == before
    new = renderer.created[len(before) :]
    assert new == [f"pipeline:steep:{OFFSCREEN}"]  # steep reuses every texture


def test_distance_builds_only_the_plain_map_and_the_refined_one_when_selected(gpu, tmp_path):
    """Model only what a scene needs: `distance` builds the plain volume alone; the refined volumes come with
    `distance_refined` (which reuses the depth map)."""
    from .scenes import plane_scene

    path = tmp_path / "scene.toml"
    path.write_text(plane_scene("distance").replace('techniques = ["distance"]',
                                                    'techniques = ["distance", "distance_refined"]'))
    renderer = Renderer(load_scene(path), gpu)
    renderer.render("distance", (32, 32))
    built = [c for c in renderer.created if c.startswith("texture:")]
    assert "texture:m.distance" in built and "texture:m.distance_refined" not in built
    before = len(renderer.created)
    renderer.render("distance_refined", (32, 32))
    assert [c for c in renderer.created[before:] if c.startswith("texture:")] == ["texture:m.distance_refined"]


def test_grazing_camera_renders_finite(gpu):
    """A camera almost in the plane: every traced value stays finite."""
    from dataclasses import replace

    scene = load_scene(default_scene_path())
    camera = replace(scene.camera, position=(0.0, 0.002, 3.0), target=(0.0, 0.0, -3.0))
    renderer = Renderer(scene, gpu)
    for technique in ("parallax", "steep", "pom"):
        image = renderer.render(technique, (96, 64), camera)
        assert np.isfinite(image.data).all()


def test_opengl_backend_draws_the_same_picture(adapter):
    """The OpenGL backend (no float32 filtering, no float32 render targets) matches the default one."""
    from wgpuviewer.core.gpu import BACKENDS, get_gpu, list_adapters

    if not any(a.info.get("backend_type") == BACKENDS["gl"] for a in list_adapters()):
        pytest.skip("no OpenGL adapter")
    scene = load_scene(default_scene_path())
    gl = Renderer(scene, get_gpu("gl", quiet=True)).render("pom", (160, 90))
    default = Renderer(scene, get_gpu("auto", quiet=True)).render("pom", (160, 90))
    diff = np.abs(gl.color.astype(np.int16) - default.color.astype(np.int16))
    assert diff.mean() < 0.5 and (diff.max(axis=2) > 16).mean() < 0.002
    assert np.isfinite(gl.data[gl.covered]).all()
