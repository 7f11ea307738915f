"""The Python API (wgpuviewer.api): render into arrays, one renderer per scene, cameras and relief settings checked
like the CLI's, a quiet first GPU use, and a package import that loads nothing heavy."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

import wgpuviewer
from tests.relief.scenes import material_scene
from wgpuviewer import api, cli
from wgpuviewer.core.errors import UserError
from wgpuviewer.scene import default_scene_path, load_scene, parse_scene

SIZE = (32, 24)


@pytest.fixture
def small_scene(tmp_path) -> Path:
    """A 2x2 plane with a 64x64 bumps relief (2x2 tiles) and a box behind it: quick to prepare on any adapter."""
    path = tmp_path / "small.toml"
    material = 'albedo = { builtin = "bumps", size = [64, 64] }\nheight = { builtin = "bumps", size = [64, 64] }\n' \
               "height_scale = 0.08\nuv_scale = [2.0, 2.0]"
    box = '[[objects]]\ntype = "box"\nmaterial = "m"\nsize = [0.3, 0.3, 0.3]\nposition = [0.5, 0.15, -0.5]'
    path.write_text(material_scene(["basic", "pom"], material, position=(0.0, 1.2, 2.0), extra=box))
    return path


def test_the_package_exports_the_api_without_loading_it():
    """`import wgpuviewer` (and so every module of it, core.commands first) loads neither wgpu nor OpenCV; the exported
    names load the API on first use."""
    code = ("import sys, wgpuviewer, wgpuviewer.core.commands; heavy = {'wgpu', 'cv2', 'numpy'} & set(sys.modules); "
            "assert not heavy, heavy; assert wgpuviewer.render.__module__ == 'wgpuviewer.api'")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert set(wgpuviewer.__all__) == {"CameraSpec", "render", "view"}
    assert wgpuviewer.CameraSpec is api.CameraSpec
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        wgpuviewer.nope  # noqa: B018 - the lookup is the test


def test_render_and_the_cli_share_the_default_size():
    assert api.DEFAULT_SIZE == cli.DEFAULT_SIZE


def test_render_gives_each_mode_as_the_cli_writes_it(small_scene, tmp_path, capsys, adapter):
    """The array of render() is the .npy of `wgpuviewer render` with the same settings (camera included)."""
    color = wgpuviewer.render(small_scene, "pom", SIZE)
    assert color.shape == (24, 32, 3) and color.dtype == np.float32
    assert color.min() >= 0.0 and color.max() <= 1.0 and color.std() > 0.01
    rgba = wgpuviewer.render(small_scene, "pom", SIZE, alpha=True)
    np.testing.assert_array_equal(rgba[:, :, :3], color)
    assert set(np.unique(rgba[:, :, 3])) == {0.0, 1.0}  # the background above the plane, the plane
    uv = wgpuviewer.render(small_scene, "pom", SIZE, {"view_angle": 50}, "uv", height_scale=0.05, uv_scale=3)
    out = tmp_path / "uv.npy"
    assert cli.main(["render", str(small_scene), "-o", str(out), "--technique", "pom", "--size", "32x24",
                     "--mode", "uv", "--view-angle", "50", "--height-scale", "0.05", "--uv-scale", "3"]) == 0
    np.testing.assert_array_equal(uv, np.load(out))
    assert uv.shape == (24, 32, 2) and np.isnan(uv).any() and np.isfinite(uv).any()


def test_repeated_renders_reuse_the_scene_renderer(small_scene, adapter):
    """One renderer per scene: a second render of an equal scene (loaded again from its path) builds nothing new."""
    wgpuviewer.render(small_scene, "pom", SIZE)
    renderer = api._renderers[-1][2]
    built = list(renderer.created)
    again = wgpuviewer.render(str(small_scene), "pom", SIZE, camera={"fov": 30}, mode="cost")
    assert api._renderers[-1][2] is renderer and renderer.created == built
    assert again.shape == (24, 32)
    wgpuviewer.render(small_scene, "pom", SIZE, height_scale=0.02)  # another relief: another renderer
    assert api._renderers[-1][2] is not renderer
    assert len(api._renderers) <= api.MAX_RENDERERS


@pytest.mark.parametrize("kwargs, fragments", [
    ({"size": (0, 10)}, ["size = (0, 10)", "integers 1 to 16384"]),
    ({"size": "32x24"}, ["size = '32x24'", "(width, height)"]),
    ({"mode": "nope"}, ["mode = 'nope'", "color"]),
    ({"scene": 42}, ["scene = 42", ".toml path"]),
    ({"technique": "nope"}, ["technique = 'nope'", "unknown technique"]),
    ({"camera": "above"}, ["camera = 'above'", "CameraSpec"]),
    ({"camera": {"angle": 3}}, ["camera: unknown key 'angle'", "view_angle"]),
    ({"camera": {"fov": 0}}, ["camera.fov = 0", "1 (exclusive) to 179 (exclusive)"]),
    ({"camera": {"position": (0, 1)}}, ["camera.position = (0, 1)", "3 numbers"]),
    ({"camera": {"target": (0, math.nan, 0)}}, ["camera.target", "finite"]),
    ({"camera": {"view_angle": 90}}, ["camera.view_angle = 90", "0 to 90 (exclusive)"]),
    ({"camera": {"view_angle": 10, "position": (0, 1, 2)}}, ["camera.view_angle = 10", "give one of"]),
    ({"camera": {"position": (0, 0, 0)}}, ["camera.position = (0, 0, 0)", "at its target"]),
    ({"camera": {"position": (0, 0, 90)}}, ["camera.position", "far plane at 50"]),
    ({"height_scale": -0.1}, ["height_scale = -0.1", "0 to 1"]),
    ({"height_scale": True}, ["height_scale = True", "a number"]),
    ({"uv_scale": (1, 2, 3)}, ["uv_scale = (1, 2, 3)", "two (u, v)"]),
    ({"uv_scale": 0}, ["uv_scale = 0", "above 0"]),
    ({"uv_scale": 1e9}, ["uv_scale = 1000000000.0", "float32 addresses every texel"]),
    ({"filter": "nope"}, ["filter = 'nope'", "unknown filter"]),
    ({"material": 5}, ["material = 5", "a material folder's path"]),
    ({"backend": "nope"}, ["backend = 'nope'", "expected one of auto, vulkan"]),
    ({"shadows": "dark"}, ["shadows = 'dark'", "off, hard, soft"]),
])
def test_bad_arguments_are_one_line_errors_before_the_gpu_starts(monkeypatch, kwargs, fragments):
    def no_gpu(*args, **kw):
        raise AssertionError("the GPU started before the arguments were checked")

    monkeypatch.setattr("wgpuviewer.core.gpu.get_gpu", no_gpu)
    calls = (wgpuviewer.render,) if "mode" in kwargs else (wgpuviewer.render, wgpuviewer.view)
    for call in calls:  # view checks its arguments as render does
        with pytest.raises(ValueError) as error:
            call(**{"size": SIZE, **kwargs})
        message = str(error.value)
        assert "\n" not in message and "--" not in message  # the API's names, not the CLI's options
        for fragment in fragments:
            assert fragment in message, message


def test_file_problems_are_value_errors_naming_the_file(tmp_path):
    """A scene file or material folder the API cannot use: an ApiError (a ValueError, still a UserError for the
    CLI), the file named, no CLI option."""
    broken = tmp_path / "broken.toml"
    broken.write_text("[camera\n")
    for kwargs, fragment in (({"scene": broken}, "broken.toml"), ({"scene": tmp_path}, "is a directory"),
                             ({"material": tmp_path / "none"}, "material = ")):
        with pytest.raises(ValueError) as error:
            wgpuviewer.render(**{"size": SIZE, **kwargs})
        assert isinstance(error.value, UserError | api.ArgumentError) and fragment in str(error.value)
        assert "--" not in str(error.value)


def test_renders_from_threads_match_the_single_threaded_ones(small_scene, adapter):
    """Four threads rendering one kept renderer at different cameras at once get each its own camera's image."""
    angles = (20, 45, 70)
    expected = {a: wgpuviewer.render(small_scene, "pom", SIZE, {"view_angle": a}) for a in angles}
    results = []

    def work(k):
        for i in range(3):
            angle = angles[(i + k) % len(angles)]
            results.append((angle, wgpuviewer.render(small_scene, "pom", SIZE, {"view_angle": angle})))

    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert len(results) == 12
    assert all(np.array_equal(image, expected[angle]) for angle, image in results)


def test_a_missing_scene_file_names_it():
    with pytest.raises(UserError, match="no_such.toml: scene file not found"):
        wgpuviewer.render("no_such.toml", size=SIZE)


def test_an_argument_error_keeps_argument_value_and_reason_apart_for_the_cli():
    """The API names its own arguments; the CLI words the same error with the options that set them."""
    from wgpuviewer.cli_render import RENDER_OPTIONS, option_label

    with pytest.raises(api.ArgumentError) as error:
        api.camera_for(load_scene(default_scene_path()), {"view_angle": 30, "position": (0, 1, 2)})
    assert (error.value.argument, error.value.value) == ("view_angle", 30)
    assert str(error.value) == ("camera.view_angle = 30: camera.position places the camera too; give one of "
                                "camera.position and camera.view_angle")
    assert error.value.worded(RENDER_OPTIONS, option_label) == (
        "--view-angle 30: --camera places the camera too; give one of --camera and --view-angle")
    with pytest.raises(api.ArgumentError) as error:
        wgpuviewer.render(technique="nope", size=SIZE)
    assert error.value.worded(RENDER_OPTIONS, option_label).startswith("--technique = 'nope': unknown technique;")


def _angle(a, b) -> float:
    return math.degrees(math.acos(np.clip(np.dot(a, b) / np.linalg.norm(a) / np.linalg.norm(b), -1, 1)))


@pytest.mark.parametrize("degrees", [0.0, 30.0, 75.0, 89.0])
def test_view_angle_places_the_camera_at_that_angle_from_the_normal(degrees):
    """The camera looks at the scene camera's target from its distance, at the angle asked from the first plane's
    normal, on the scene camera's side (its azimuth); a view straight down takes the scene's view direction as up."""
    scene = load_scene(default_scene_path())
    camera = api.camera_for(scene, {"view_angle": degrees})
    base = scene.camera
    to_camera = np.subtract(camera.position, camera.target)
    assert camera.target == base.target and camera.fov == base.fov
    assert _angle(to_camera, (0, 1, 0)) == pytest.approx(degrees, abs=1e-9)
    assert np.linalg.norm(to_camera) == pytest.approx(np.linalg.norm(np.subtract(base.position, base.target)))
    if degrees > 0:  # the default camera looks from +Z: so does this one
        assert _angle(to_camera * [1, 0, 1], (0, 0, 1)) == pytest.approx(0, abs=1e-6)
    assert np.linalg.norm(np.cross(camera.up, to_camera)) > 1e-3  # never along the view
    if degrees == 0:
        assert camera.up == pytest.approx((0, 0, -1))  # the scene camera looks towards -Z: that is up


def test_view_angle_follows_a_rotated_subject_and_a_given_target():
    """The subject is the first plane (here after a box); its normal turns with its rotation."""
    scene = parse_scene("""
objects = [  # the box first: the subject is the first plane
    { type = "box", material = "m", size = [1.0, 1.0, 1.0], position = [2.0, 0.5, 0.0] },
    { type = "plane", material = "m", size = [2.0, 2.0], rotation = [90.0, 0.0, 0.0] },
]
[camera]
position = [0.0, 0.5, 3.0]
target = [0.0, 0.5, 0.0]
[materials.m]
albedo = [0.5, 0.5, 0.5]
""")
    assert api.subject(scene) == 1
    normal = api.surface_normal(scene)
    assert normal == pytest.approx((0, 0, 1))  # the plane stands up, facing +Z
    camera = api.camera_for(scene, api.CameraSpec(view_angle=40, target=(0.2, 0.1, 0.0)))
    assert camera.target == (0.2, 0.1, 0.0)
    assert _angle(np.subtract(camera.position, camera.target), normal) == pytest.approx(40, abs=1e-9)


def test_position_target_and_fov_replace_the_scene_camera_values():
    scene = load_scene(default_scene_path())
    camera = api.camera_for(scene, {"position": [1, 2, 3], "fov": 30})
    assert (camera.position, camera.target, camera.fov, camera.up) == ((1, 2, 3), scene.camera.target, 30, (0, 1, 0))
    assert api.camera_for(scene) == scene.camera
    top = api.camera_for(scene, {"position": (0, 3, 0), "target": (0, 0, 0)})  # along up: up is the view direction
    assert top.up == pytest.approx(tuple(np.array([0, -1.4, -3.2]) * [0, 0, 1] / 3.2))


def test_relief_settings_change_the_subject_material_only():
    scene = load_scene(default_scene_path())
    changed = api.with_relief(scene, height_scale=0.2, uv_scale=(3, 1))
    bricks, bumps = changed.materials["bricks"], changed.materials["bumps"]
    assert (bricks.height_scale, bricks.uv_scale) == (0.2, (3.0, 1.0))
    assert bumps == scene.materials["bumps"]
    assert api.with_relief(scene, uv_scale=4).materials["bricks"].uv_scale == (4.0, 4.0)
    assert api.with_relief(scene) is scene


def test_the_first_gpu_use_is_quiet(tmp_path, adapter):
    """No driver line about XDG_RUNTIME_DIR on a process that did not set it up (the API's own setup does): at
    most the one-line notice of a software adapter."""
    env = {k: v for k, v in os.environ.items() if k != "XDG_RUNTIME_DIR"}
    code = "import wgpuviewer; print(wgpuviewer.render(size=(8, 6), technique='basic').shape)"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, env=env,
                            cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "(6, 8, 3)"
    noise = [line for line in result.stderr.splitlines() if line and not line.startswith("notice: no hardware GPU")]
    assert not noise, result.stderr
