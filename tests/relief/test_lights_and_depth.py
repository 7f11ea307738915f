"""Scene limits that used to fail silently: every light counts (up to the named limit, refused beyond it), and a
tiny camera.near renders the same picture (reversed-Z float depth) instead of an empty one."""

from __future__ import annotations

import numpy as np
import pytest

from tests.relief.scenes import material_scene
from wgpuviewer.core.errors import UserError
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.scene import MAX_LIGHTS, parse_scene

BOX = """
[[objects]]
type = "box"
material = "m"
size = [0.5, 0.5, 0.5]
position = [0.0, 0.25, 0.3]
"""

DIM = """
[[lights]]
type = "directional"
direction = [0.0, -1.0, 0.0]
color = [0.05, 0.05, 0.05]
"""

RED = """
[[lights]]
type = "point"
position = [{x}, 0.6, 0.5]
color = [1.0, 0.0, 0.0]
intensity = 2.0
"""


def scene(lights: str, near: float = 0.05):
    return parse_scene(material_scene(["basic", "pom"], 'albedo = [0.6, 0.6, 0.6]\nheight = "builtin:bumps"',
                                      position=(0.0, 1.2, 2.0), camera=f"near = {near}\nfar = 50.0",
                                      extra=BOX + lights))


@pytest.mark.requires_gpu
def test_lights_past_the_fourth_count(gpu):
    four = DIM * 4
    images = [Renderer(scene(four + extra), gpu).render("basic", (64, 48)).color[..., :3].astype(int)
              for extra in ("", RED.format(x=-0.5), RED.format(x=-0.5) + RED.format(x=0.5))]
    red = [img[..., 0].mean() - img[..., 1].mean() for img in images]
    assert red[0] < 1 < red[1] < red[2], red  # the 5th light shows, and the 6th adds to it


def test_more_lights_than_the_limit_are_refused_with_the_limit_named():
    scene(DIM * MAX_LIGHTS)  # at the limit: fine
    with pytest.raises(UserError, match=f"lights: {MAX_LIGHTS + 1} \\[\\[lights\\]\\] tables; expected at most "
                                        f"{MAX_LIGHTS}"):
        scene(DIM * (MAX_LIGHTS + 1))


@pytest.mark.requires_gpu
@pytest.mark.parametrize("technique", ["basic", "pom"])
def test_a_tiny_near_plane_renders_the_same_picture(gpu, technique):
    reference = Renderer(scene(DIM), gpu).render(technique, (64, 48))
    assert reference.covered.mean() > 0.2
    for near in (1e-9, 5e-11):
        tiny = Renderer(scene(DIM, near), gpu).render(technique, (64, 48))
        assert (tiny.covered == reference.covered).all()
        assert np.abs(tiny.color.astype(int) - reference.color.astype(int)).max() <= 1, near  # box still in front


def test_a_near_plane_too_small_for_the_far_plane_is_refused_with_the_range():
    with pytest.raises(UserError, match=r"camera.near = 1e-13: too small for camera.far = 50; expected camera.near "
                                        r">= far / 1e\+12 = 5e-11"):
        scene(DIM, 1e-13)
