"""`wgpuviewer render --camera/--target/--fov/--view-angle/--height-scale/--uv-scale`: what each changes, bad values
as one line (exit 2), and the help that defines the view angle."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from tests.relief.scenes import material_scene
from wgpuviewer import api, cli
from wgpuviewer.scene import load_scene


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "plane.toml"
    material = 'albedo = { builtin = "bumps", size = [64, 64] }\nheight = { builtin = "bumps", size = [64, 64] }\n' \
               "height_scale = 0.08"
    path.write_text(material_scene(["basic", "pom"], material, position=(0.0, 1.0, 1.6)))
    return path


@pytest.fixture
def material_folder(tmp_path):
    """A 16x16 texture set by generic names: albedo and a height of ridges."""
    folder = tmp_path / "set"
    folder.mkdir()
    x = np.arange(16) / 16
    height = np.tile(0.5 + 0.5 * np.sin(2 * np.pi * x), (16, 1))
    assert cv2.imwrite(str(folder / "albedo.png"), np.dstack([height * 200, height * 100 + 50, 90 + 0 * height]))
    assert cv2.imwrite(str(folder / "height.png"), np.rint(height * 255).astype(np.uint8))
    return folder


def render_npy(tmp_path, *args) -> np.ndarray:
    out = tmp_path / "out.npy"
    assert cli.main(["render", *map(str, args), "-o", str(out), "--size", "32x24"]) == 0
    return np.load(out)


def test_view_angle_is_the_camera_it_computes(scene_file, tmp_path, capsys, adapter):
    """--view-angle renders exactly what --camera at the position it defines renders (one camera function), and a
    negative coordinate passes with '='."""
    camera = api.camera_for(load_scene(scene_file), {"view_angle": 65})
    by_angle = render_npy(tmp_path, scene_file, "--mode", "uv", "--view-angle", 65)
    by_position = render_npy(tmp_path, scene_file, "--mode", "uv", "--camera=" + ",".join(map(repr, camera.position)))
    np.testing.assert_array_equal(by_angle, by_position)
    assert np.isfinite(by_angle).mean() > 0.3
    side = render_npy(tmp_path, scene_file, "--mode", "uv", "--camera=-1.2,0.6,0.4", "--target", "0,0,0.2")
    assert not np.array_equal(np.isnan(side), np.isnan(by_angle))


def test_fov_narrows_the_view(scene_file, tmp_path, capsys, adapter):
    wide = render_npy(tmp_path, scene_file, "--mode", "uv", "--technique", "basic")
    narrow = render_npy(tmp_path, scene_file, "--mode", "uv", "--technique", "basic", "--fov", 15)
    span = lambda uv: np.nanmax(uv[:, :, 0]) - np.nanmin(uv[:, :, 0])  # noqa: E731
    assert span(narrow) < 0.5 * span(wide)


def test_uv_scale_and_height_scale_of_a_material_folder(scene_file, material_folder, tmp_path, capsys, adapter):
    """On the plane --material shows: --uv-scale multiplies the hit UV (basic: no offset); --height-scale 0 makes
    POM's hits those of basic texturing, a deeper relief moves them."""
    shown = (scene_file, "--material", material_folder, "--mode", "uv")
    once = render_npy(tmp_path, *shown, "--technique", "basic")
    thrice = render_npy(tmp_path, *shown, "--technique", "basic", "--uv-scale", 3)
    covered = np.isfinite(once[:, :, 0])
    np.testing.assert_allclose(thrice[covered], 3 * once[covered], rtol=1e-4, atol=1e-4)
    stretched = render_npy(tmp_path, *shown, "--technique", "basic", "--uv-scale", "2,1")
    np.testing.assert_allclose(stretched[covered][:, 0], 2 * once[covered][:, 0], rtol=1e-4, atol=1e-4)
    flat = render_npy(tmp_path, *shown, "--technique", "pom", "--height-scale", 0)
    np.testing.assert_allclose(flat[covered], once[covered], atol=1e-4)
    deep = render_npy(tmp_path, *shown, "--technique", "pom", "--height-scale", 0.2)
    assert np.nanmax(np.abs(deep[covered] - once[covered])) > 0.02  # hits leaving the face: discarded


def bad(option: str, *cases) -> list:
    """(args, fragments) of each (value, how the line shows the option, what it says) given to ``option``."""
    return [([option, value], [shown, says]) for value, shown, says in cases]


@pytest.mark.parametrize("args, fragments", [
    *bad("--camera", ("1,2", "--camera '1,2'", "X,Y,Z"), ("a,b,c", "--camera 'a,b,c'", "numbers"),
         ("0,0,0", "--camera 0,0,0", "at its target"), ("0,0,80", "--camera 0,0,80", "far plane")),
    *bad("--target", ("nan,0,0", "--target nan,0,0", "finite")),
    *bad("--fov", ("180", "--fov 180", "1 (exclusive) to 179 (exclusive)"), ("wide", "--fov", "invalid float value")),
    *bad("--view-angle", ("-5", "--view-angle -5", "0 to 90 (exclusive)")),
    (["--view-angle", "30", "--camera", "0,1,2"], ["--view-angle 30", "give one of --camera and --view-angle"]),
    *bad("--height-scale", ("1.5", "--height-scale 1.5", "0 to 1")),
    *bad("--uv-scale", ("0,1", "--uv-scale 0", "above 0"), ("1,2,3", "--uv-scale '1,2,3'", "U,V"),
         ("1e9", "--uv-scale 1e+09", "texel coordinates")),
])
def test_bad_values_are_one_line_exit_2(args, fragments, tmp_path, capsys):
    out = tmp_path / "x.png"
    assert cli.main(["render", "-o", str(out), "--size", "8x8", *args]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("wgpuviewer: error: "), lines
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    assert not out.exists()


def test_help_defines_the_view_angle(capsys):
    assert cli.main(["render", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    for option in ("--camera X,Y,Z", "--target X,Y,Z", "--fov DEG", "--view-angle DEG", "--height-scale H",
                   "--uv-scale S|U,V"):
        assert option in text
    assert "at DEG degrees from the surface normal: 0 looks straight down onto it" in text
    assert "the scene's first plane (where --material shows its folder)" in text


def test_view_angle_needs_a_subject_with_one_normal(tmp_path, capsys):
    """A sphere subject has no single normal to measure a view angle from: one line, exit 2, naming the fix."""
    path = tmp_path / "sphere.toml"
    material = 'albedo = { builtin = "bumps", size = [32, 32] }\nheight = { builtin = "bumps", size = [32, 32] }'
    text = material_scene(["basic"], material).replace('type = "plane"', 'type = "sphere"').replace(
        "size = [2.0, 2.0]", "size = [0.5]")
    path.write_text(text)
    out = tmp_path / "x.png"
    assert cli.main(["render", str(path), "-o", str(out), "--size", "8x8", "--view-angle", "40"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "--view-angle 40" in lines[0] and "is a sphere" in lines[0] and "--camera" in lines[0]
    assert not out.exists()
