"""The hardware rasteriser's texture coordinates for the study's quad: the scene renderer draws the quad with
``basic`` (whose hit uv is the interpolated uv) offscreen, and its raw ``uv`` data is read back, in texels.

The rasteriser gets what any scene gives it: float32 vertex positions and uv, the float32 model and
view-projection matrices, ``uv * uv_scale`` in the vertex shader; it clips, interpolates perspective-correctly and
writes the uv of each pixel centre. Pixels it does not cover come back flagged.
"""

from __future__ import annotations

import numpy as np
import wgpu

from wgpuviewer.core.gpu import Gpu
from wgpuviewer.relief.renderer import DrawConfig, Renderer
from wgpuviewer.relief.targets import COLOR_FORMAT, DEPTH_FORMAT
from wgpuviewer.scene import parse_scene

from .geometry import Quad, scene_toml
from .methods import Result

TECHNIQUE = "basic"


def renderer_for(quad: Quad, gpu: Gpu) -> Renderer:
    if quad.horizon:
        raise ValueError("the rasteriser draws finite quads only; this setup sees past the wall's horizon")
    return Renderer(parse_scene(scene_toml(quad)), gpu)


def hardware_uv(quad: Quad, gpu: Gpu, renderer: Renderer | None = None) -> Result:
    """The rasteriser's u, v (texels, float32 from the GPU, scaled in float64) of every pixel of ``quad``'s frame."""
    renderer = renderer or renderer_for(quad, gpu)
    image = renderer.render(DrawConfig.of(TECHNIQUE), quad.frame, camera=quad.camera)
    texels = float(quad.setup.texture_size)
    flagged = ~image.covered
    u = np.where(flagged, 0.0, image.data[..., 0].astype(np.float64) * texels)
    v = np.where(flagged, 0.0, image.data[..., 1].astype(np.float64) * texels)
    return Result(u, v, flagged)


def frame_recorder(quad: Quad, renderer: Renderer):
    """A core.pass_timing recorder: one render pass of the quad (``basic``, colour target, as the window draws)."""
    device = renderer.gpu.device
    w, h = quad.frame
    usage = wgpu.TextureUsage.RENDER_ATTACHMENT
    color = device.create_texture(label="perspective:color", size=(w, h, 1), format=COLOR_FORMAT, usage=usage)
    depth = device.create_texture(label="perspective:depth", size=(w, h, 1), format=DEPTH_FORMAT, usage=usage)
    views = [color.create_view()], depth.create_view()
    draw = DrawConfig.of(TECHNIQUE)

    def record(encoder, timestamp_writes=None):
        renderer.encode(encoder, views[0], views[1], (COLOR_FORMAT,), draw, quad.camera, quad.frame,
                        timestamp_writes=timestamp_writes)

    return record
