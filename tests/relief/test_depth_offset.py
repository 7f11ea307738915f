"""depth_offset: a relief material writes its traced hit's depth, so a box sunk into a relief floor shows where the
relief is lower than the box's top and hides where it is higher."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.relief.renderer import DrawConfig, Renderer
from wgpuviewer.scene import parse_scene

SIZE = (96, 96)
HEIGHT_SCALE = 0.2  # uv units: on a 2x2 plane (2 world units per uv unit) the relief is 0.4 deep
BOX_TOP = -0.1  # world y: layer depth 0.1 / 0.4 = 0.25 in the relief


def scene(tmp_path, depth_offset: bool, box: bool = True) -> str:
    height = np.zeros((32, 32), np.float32)
    height[:, :16] = 1.0  # u < 0.5 high (at the surface), u >= 0.5 low (0.4 below it)
    np.save(tmp_path / "height.npy", height)
    box_lines = f"""
[[objects]]
type = "box"
material = "green"
size = [1.0, 0.2, 1.0]
position = [0.0, {BOX_TOP - 0.1}, 0.0]
""" if box else ""
    return f"""
[scene]
techniques = ["maxmip"]
[camera]
position = [0.0, 2.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov = 50
[materials.floor]
albedo = [1.0, 0.0, 0.0]
height = "{tmp_path / 'height.npy'}"
height_scale = {HEIGHT_SCALE}
depth_offset = {str(depth_offset).lower()}
[materials.green]
albedo = [0.0, 1.0, 0.0]
[[objects]]
type = "plane"
material = "floor"
size = [2.0, 2.0]
{box_lines}
"""


def is_green(image) -> np.ndarray:
    """The green box's pixels (the floor is red; both get the same white specular)."""
    color = image.color[..., :3].astype(int)
    return color[..., 1] > color[..., 0] + 60


@pytest.mark.requires_gpu
def test_a_sunk_box_shows_where_the_relief_is_lower_than_its_top(gpu, tmp_path):
    floor = Renderer(parse_scene(scene(tmp_path, True, box=False)), gpu).render("maxmip", SIZE)
    depth = floor.data[..., 2]  # the floor's hit layer depth per pixel, from the known height map: 0 or 1
    hit_u = floor.data[..., 0]
    assert floor.covered.all()
    low = (depth > 0.99) & (hit_u > 0.5)
    high = (depth < 0.01) & (hit_u < 0.5)
    assert low.mean() > 0.3 and high.mean() > 0.3  # the map's two halves, where the camera sees them
    offset = Renderer(parse_scene(scene(tmp_path, True)), gpu)
    image = offset.render("maxmip", SIZE)
    assert any("+depth_offset" in c for c in offset.created)
    green = is_green(image)
    # the box (x, z in [-0.5, 0.5]: the middle half of the picture) sits 0.25 deep in the relief
    box = np.zeros(green.shape, bool)
    box[SIZE[1] // 4 + 3: 3 * SIZE[1] // 4 - 3, SIZE[0] // 4 + 3: 3 * SIZE[0] // 4 - 3] = True
    assert green[box & low].mean() > 0.95, "the box is hidden where the relief is below its top"
    assert not green[high].any(), "the box shows through where the relief is above its top"
    # without depth_offset the floor's polygon (at the surface) hides the whole box
    plain = Renderer(parse_scene(scene(tmp_path, False)), gpu).render("maxmip", SIZE)
    assert not is_green(plain).any()


@pytest.mark.requires_gpu
def test_the_draw_overrides_each_materials_depth_offset(gpu, tmp_path):
    """DrawConfig.depth_offset (the viewer's Z) turns the hit's depth on for a material without it, and off for one
    with it: the same pictures as the materials' own settings."""
    own_on = Renderer(parse_scene(scene(tmp_path, True)), gpu).render("maxmip", SIZE)
    own_off = Renderer(parse_scene(scene(tmp_path, False)), gpu)
    forced_on = own_off.render(DrawConfig.of("maxmip", depth_offset=True), SIZE)
    assert is_green(forced_on).mean() > 0.05
    assert np.array_equal(forced_on.color, own_on.color)
    forced_off = Renderer(parse_scene(scene(tmp_path, True)), gpu).render(DrawConfig.of("maxmip", depth_offset=False),
                                                                          SIZE)
    assert not is_green(forced_off).any()
