"""Silhouettes: ``address = "clamp"`` makes the uv square the relief's extent; a ray that leaves it before meeting
the relief is discarded, so the relief's edge shows its steps. ``repeat`` tiles the relief on past the face's edge
and covers the whole face."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.scene import parse_scene

SIZE = (96, 72)


def scene(address: str, kind: str) -> str:
    size = "[1.0, 1.0]" if kind == "quad" else "[1.0, 1.0, 1.0]"
    return f"""
scene = {{ techniques = ["maxmip", "basic"] }}
camera = {{ position = [1.1, 0.8, 1.6], target = [0.0, 0.0, 0.0], fov = 60 }}
[materials.m]
albedo = [0.8, 0.8, 0.8]
height = {{ builtin = "bricks", size = [64, 64] }}
height_scale = 0.15
address = "{address}"
[[objects]]
type = "{kind}"
material = "m"
size = {size}
"""


@pytest.mark.requires_gpu
@pytest.mark.parametrize("kind", ["quad", "box"])
def test_clamp_discards_rays_leaving_the_uv_square_along_the_edges_repeat_covers(gpu, kind):
    repeat = Renderer(parse_scene(scene("repeat", kind)), gpu)
    polygon = repeat.render("basic", SIZE).covered  # what the faces cover, undisplaced
    tiled = repeat.render("maxmip", SIZE)
    assert (tiled.covered == polygon).all(), "repeat covers every pixel of the faces"
    clamp = Renderer(parse_scene(scene("clamp", kind)), gpu)
    clamped = clamp.render("maxmip", SIZE)
    assert any("+clamp" in c for c in clamp.created)
    discarded = polygon & ~clamped.covered
    assert discarded.sum() >= 20, "no silhouette"
    assert not (clamped.covered & ~polygon).any()
    uv = clamped.data[clamped.covered][:, :2]
    assert ((uv >= 0.0) & (uv <= 1.0)).all(), "a clamped hit outside the uv square"
    # the discarded pixels lie along the faces' edges: within a few pixels of an edge of the polygon's image or of
    # a crease between faces (the relief is 0.15 uv deep: its steps reach that far in)
    edges = polygon ^ ndimage.binary_erosion(polygon)
    basic_uv = repeat.render("basic", SIZE).data[..., :2]
    seams = (np.abs(np.diff(basic_uv, axis=0, prepend=basic_uv[:1])) > 0.2).any(-1) | \
        (np.abs(np.diff(basic_uv, axis=1, prepend=basic_uv[:, :1])) > 0.2).any(-1)
    near_edge = ndimage.binary_dilation(edges | (seams & polygon), iterations=12)
    assert near_edge[discarded].all()
