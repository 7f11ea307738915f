"""Output modes: `depth` is camera depth (the traced hit's distance from the camera along its view axis),
`layer_depth` the hit's depth inside the relief, and pictures can carry alpha (transparent background)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from wgpuviewer import cli
from wgpuviewer.relief.output import OUTPUT_MODES, mode_data, mode_picture
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.scene import parse_scene

from .scenes import plane_scene

SIZE = (32, 24)
CAMERA = (0.1, 0.5, 0.8)
HEIGHT_SCALE = 0.08


@pytest.fixture(scope="module")
def plane(gpu):
    """A unit plane at y = 0 tiled twice (one uv unit: half a world unit), with a bumps relief, and its renders:
    basic (no search: the flat surface) and pom."""
    text = plane_scene("pom", "layers = 64", position=CAMERA, height_scale=HEIGHT_SCALE, map_size=32)
    scene = parse_scene(text.replace("height_scale =", "uv_scale = [2.0, 2.0]\nheight_scale ="))
    renderer = Renderer(scene, gpu)
    return scene, renderer.render("basic", SIZE), renderer.render("pom", SIZE)


def test_depth_of_the_flat_surface_is_its_distance_along_the_view_axis(plane):
    """The basic technique's hit is the surface point itself: from its uv the point on the plane (u, v in [0, 2]
    over x, z in [-0.5, 0.5]), whose view depth is (P - camera) . forward."""
    scene, flat, _ = plane
    covered = flat.covered
    assert covered.mean() > 0.3
    uv, depth = mode_data(flat, "uv"), mode_data(flat, "depth")
    assert depth.dtype == np.float32 and np.isnan(depth[~covered]).all()
    points = np.stack([uv[..., 0] / 2 - 0.5, np.zeros(uv.shape[:2]), uv[..., 1] / 2 - 0.5], axis=-1)
    forward = -np.asarray(CAMERA) / np.linalg.norm(CAMERA)  # the camera looks at the origin
    expected = (points - np.asarray(CAMERA)) @ forward
    np.testing.assert_allclose(depth[covered], expected[covered], rtol=2e-4)
    assert scene.camera.near < np.nanmin(depth) < np.nanmax(depth) < scene.camera.far


def test_depth_of_a_relief_hit_lies_on_the_eye_ray_below_the_surface(plane):
    """POM's hit is on the eye ray, its layer depth t times height_scale uv units (half a world unit each) below
    the plane: along the ray the view depth grows like the drop below the camera, so it is the flat depth times
    (camera height + drop) / camera height."""
    _, flat, relief = plane
    both = flat.covered & relief.covered
    t = mode_data(relief, "layer_depth")
    assert both.mean() > 0.3 and np.nanmax(t) > 0.2  # the relief is really traced
    drop = t * HEIGHT_SCALE * 0.5
    expected = mode_data(flat, "depth") * (CAMERA[1] + drop) / CAMERA[1]
    np.testing.assert_allclose(mode_data(relief, "depth")[both], expected[both], rtol=1e-3)
    assert np.array_equal(mode_data(relief, "layer_depth"), t, equal_nan=True)  # its own mode, unchanged


def test_every_mode_has_a_picture_and_alpha_marks_what_was_drawn(plane):
    _, _, relief = plane
    covered = relief.covered
    for mode in OUTPUT_MODES:
        rgb, rgba = mode_picture(relief, mode), mode_picture(relief, mode, alpha=True)
        assert rgb.shape == (*SIZE[::-1], 3) and rgba.shape == (*SIZE[::-1], 4), mode
        assert np.array_equal(rgba[..., :3], rgb) and np.array_equal(rgba[..., 3] == 255, covered), mode
    depth = mode_picture(relief, "depth")[..., 0].astype(int)
    nearest = np.nanargmin(mode_data(relief, "depth"))
    assert depth.flat[nearest] == 255  # nearest white, farthest black
    color = mode_data(relief, "color", alpha=True)
    assert color.shape == (*SIZE[::-1], 4) and np.array_equal(color[..., 3], covered.astype(np.float32))


def test_render_writes_an_rgba_png_and_raw_camera_depth(tmp_path, capsys, adapter):
    png, npy = tmp_path / "a.png", tmp_path / "d.npy"
    common = ["--size", "32x24", "--technique", "pom"]
    assert cli.main(["render", "-o", str(png), "--alpha", *common]) == 0
    assert cli.main(["render", "-o", str(npy), "--mode", "depth", *common]) == 0
    picture = cv2.imread(str(png), cv2.IMREAD_UNCHANGED)
    depth = np.load(npy)
    assert picture.shape == (24, 32, 4) and set(np.unique(picture[..., 3])) == {0, 255}
    assert depth.dtype == np.float32 and depth.shape == (24, 32)
    assert np.array_equal(picture[..., 3] == 255, np.isfinite(depth))  # drawn: opaque, with a depth
    assert (depth[np.isfinite(depth)] > 0).all()


def test_alpha_is_refused_for_a_turntable(tmp_path, capsys):
    out = tmp_path / "t.gif"
    assert cli.main(["render", "--orbit", "4", "--alpha", "-o", str(out), "--size", "16x16"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["wgpuviewer: error: --alpha: a turntable (.gif) has no alpha; drop --alpha or render single "
                   "frames to .png"]
    assert not out.exists()


def test_the_window_depth_view_shows_the_offscreen_camera_depth(gpu):
    """A one-target draw in mode "depth" (the window path: fs_view_depth, its own entry point so that fs_color's
    other modes do not pay its derivatives) paints 1 / (1 + camera depth) of the offscreen render's hits."""
    import wgpu

    from wgpuviewer.relief.targets import DEPTH_FORMAT, read_texture

    text = plane_scene("pom", "layers = 64", position=CAMERA, height_scale=HEIGHT_SCALE, map_size=32)
    renderer = Renderer(parse_scene(text), gpu)
    image = renderer.render("pom", SIZE)
    device = gpu.device
    usage = wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.COPY_SRC
    target = device.create_texture(size=(*SIZE, 1), format="rgba32float", usage=usage)
    depth = device.create_texture(size=(*SIZE, 1), format=DEPTH_FORMAT, usage=wgpu.TextureUsage.RENDER_ATTACHMENT)
    encoder = device.create_command_encoder()
    renderer.encode(encoder, [target.create_view()], depth.create_view(), ("rgba32float",), renderer.config("pom"),
                    renderer.scene.camera, SIZE, "depth")
    device.queue.submit([encoder.finish()])
    shown = read_texture(device, target, 4, np.float32)[..., 0]
    covered = image.covered
    assert covered.mean() > 0.3
    expected = 1.0 / (1.0 + mode_data(image, "depth"))
    np.testing.assert_allclose(shown[covered], expected[covered], rtol=1e-5)
    assert any(c.endswith(":depth") for c in renderer.created)  # its own pipeline
