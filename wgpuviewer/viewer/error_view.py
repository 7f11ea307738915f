"""The viewer's error view: per-pixel UV error of a technique against a reference, as a heat map.

Both the technique and the reference (POM at ``REFERENCE_LAYERS`` layers: with that many layers
and the linear refinement its hit is, at viewer resolutions, indistinguishable from the float64
exact hit) are rendered offscreen at reduced resolution with the same camera; the wrap-aware texel
distance of their hit UVs (``reference.uv_error_texels``) goes into an r32float texture that a
small fullscreen pipeline (``wgsl/entry/error_view.wgsl``) paints over the frame with the cost view's heat colours.
The overlay keeps the map it paints, and ``cost_map`` measures the cost view's fetches the same way, offscreen: the
legends' mean and p95 per half come from them (``stats.half_summaries``).
"""

from __future__ import annotations

import numpy as np
import wgpu

from wgpuviewer.core.gpu import fullscreen_pipeline
from wgpuviewer.core.structs import Struct
from wgpuviewer.core.wgsl import compose
from wgpuviewer.relief.reference import uv_error_texels
from wgpuviewer.relief.renderer import DrawConfig, Renderer

REFERENCE = "pom"
REFERENCE_LAYERS = 512
MAX_WIDTH = 400  # error maps are computed at most this wide (offscreen renders + a CPU readback)
#: The overlay's uniform (entry/error_view.wgsl uses it and does not declare it).
BLIT = Struct("Blit", [
    ("rect", "vec4f"),  # x, y, w, h of the viewport part in pixels (the scissor)
    ("max_value", "f32"),  # value shown as full heat
])


def map_size(window: tuple[int, int]) -> tuple[int, int]:
    w, h = window
    scale = min(1.0, MAX_WIDTH / max(w, 1))
    return max(1, round(w * scale)), max(1, round(h * scale))


def texel_size(renderer: Renderer) -> tuple[int, int]:
    """(W, H) of the largest depth map of the scene: UV errors are measured in its texels."""
    sizes = [renderer.texture(name, "depth").size[:2] for name in sorted({o.material for o in renderer.scene.objects})]
    return max(sizes, key=lambda s: s[0] * s[1])


def reference_render(renderer: Renderer, size, camera, height_scale: float | None = None):
    """Offscreen render of the reference (POM at REFERENCE_LAYERS layers).

    ``height_scale``: the compared technique's live override, so both trace the same relief (None: the
    materials' own scales)."""
    return renderer.render(renderer.config(REFERENCE, {"layers": REFERENCE_LAYERS}, height_scale), size, camera)


def error_map(renderer: Renderer, draw: DrawConfig, size, camera, reference=None) -> np.ndarray:
    """(H, W) float32 UV error in texels of ``draw`` against the reference; -1 where nothing was drawn.
    ``reference``: a render to reuse (made with ``reference_render`` at ``draw``'s height scale)."""
    ref = reference if reference is not None else reference_render(renderer, size, camera, draw.height_scale)
    img = renderer.render(draw, size, camera)
    covered = img.covered & ref.covered
    err = np.full(covered.shape, -1.0, np.float32)
    if covered.any():
        err[covered] = uv_error_texels(img.data[covered][:, :2], ref.data[covered][:, :2], texel_size(renderer))
    return err


def cost_map(renderer: Renderer, draw: DrawConfig, size, camera) -> np.ndarray:
    """(H, W) float32 depth fetches per pixel of ``draw``, what the cost view paints (a capped ray counts the fetches
    it made); -1 where nothing was drawn."""
    img = renderer.render(draw, size, camera)
    covered = img.covered
    fetches = np.full(covered.shape, -1.0, np.float32)
    fetches[covered] = np.abs(img.data[..., 3][covered])
    return fetches


class ErrorOverlay:
    """An r32float value texture painted as heat over (part of) the frame."""

    def __init__(self, device: wgpu.GPUDevice, target_format: str):
        self.device = device
        F = wgpu.ShaderStage.FRAGMENT
        self.layout, self.pipeline = fullscreen_pipeline(
            device, "error-view", compose(BLIT.generated(), "entry/error_view.wgsl").code,
            [{"binding": 0, "visibility": F, "buffer": {"type": "uniform"}},
             {"binding": 1, "visibility": F, "texture": {"sample_type": "unfilterable-float"}}],
            target_format,
        )
        self.texture = None
        self.group = None
        self.uniform = device.create_buffer(
            label="error-view", size=BLIT.size, usage=wgpu.BufferUsage.UNIFORM | wgpu.BufferUsage.COPY_DST
        )

    def upload(self, values: np.ndarray) -> None:
        h, w = values.shape
        if self.texture is None or self.texture.size[:2] != (w, h):
            self.texture = self.device.create_texture(
                label="error-view", size=(w, h, 1), format="r32float",
                usage=wgpu.TextureUsage.TEXTURE_BINDING | wgpu.TextureUsage.COPY_DST,
            )
            self.group = self.device.create_bind_group(
                layout=self.layout,
                entries=[
                    {"binding": 0, "resource": {"buffer": self.uniform}},
                    {"binding": 1, "resource": self.texture.create_view()},
                ],
            )
        self.device.queue.write_texture(
            {"texture": self.texture}, np.ascontiguousarray(values, np.float32),
            {"bytes_per_row": 4 * w, "rows_per_image": h}, (w, h, 1),
        )

    def encode(self, encoder, view, rect: tuple[int, int, int, int], max_value: float) -> None:
        """Paint over ``rect`` (x, y, w, h in target pixels) of ``view``; the texture spans the rect."""
        if self.group is None:
            return
        self.device.queue.write_buffer(self.uniform, 0, BLIT.pack({"rect": rect, "max_value": max(max_value, 1e-6)}))
        rpass = encoder.begin_render_pass(
            label="error-view",
            color_attachments=[{"view": view, "load_op": "load", "store_op": "store"}],
        )
        rpass.set_scissor_rect(*rect)
        rpass.set_pipeline(self.pipeline)
        rpass.set_bind_group(0, self.group)
        rpass.draw(3)
        rpass.end()
