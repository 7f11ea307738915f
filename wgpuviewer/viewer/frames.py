"""The frame encoder of the window: the scene passes (one, or the two halves of the A/B split), the error view's
overlay, a screenshot of the scene alone, then the HUD; and reading a frame back."""

from __future__ import annotations

import numpy as np

from wgpuviewer.relief.renderer import DrawConfig, Renderer
from wgpuviewer.relief.targets import DEPTH_FORMAT
from wgpuviewer.scene import Camera

from . import error_view
from .stats import split_column


def scene_passes(draws: list[DrawConfig], split_x: float | None, w: int, h: int) -> list:
    """(DrawConfig, scissor) of the passes that draw the scene: one (``split_x`` None), or the two halves of A/B."""
    if split_x is None:
        return [(draws[0], None)]
    xs = int(np.clip(round(split_x * w), 1, w - 1)) if w > 1 else 1
    return [(draws[0], (0, 0, xs, h)), (draws[1], (xs, 0, w - xs, h))]


class FrameEncoder:
    """Draws the window's frames with one renderer into textures of one format (the depth buffer and the error
    overlay are its own, sized on demand)."""

    def __init__(self, renderer: Renderer, format: str, timer=None):
        self.renderer, self.format, self.timer = renderer, format, timer
        self.device = renderer.gpu.device
        self._depth = None
        self._error = None  # ErrorOverlay, built on first use
        self._error_key = None
        self._error_time = -1e9
        self.error_texels = (1, 1)  # the error map's texel size (the legend's unit)
        self.error_values = None  # the error map the overlay paints (the legend's per-half statistics)

    def invalidate_error_view(self) -> None:
        self._error_key = None

    def update_error_view(self, draws: list[DrawConfig], split_x: float | None, size: tuple[int, int],
                          camera: Camera, now: float) -> None:
        """Recompute the error map when what it shows changed (at most ~3 times a second)."""
        size = error_view.map_size(size)
        key = (size, tuple(draws), split_x is not None and round(split_x, 3), camera)
        if key == self._error_key or (self._error_key is not None and now - self._error_time < 0.3):
            return
        if self._error is None:
            self._error = error_view.ErrorOverlay(self.device, self.format)
        # One reference per height-scale override in use (each technique is compared on its own relief).
        references = {}
        for draw in draws:
            if draw.height_scale not in references:
                references[draw.height_scale] = error_view.reference_render(self.renderer, size, camera,
                                                                            draw.height_scale)

        def error_of(draw):
            return error_view.error_map(self.renderer, draw, size, camera, references[draw.height_scale])

        values = error_of(draws[0])
        if split_x is not None:
            right = error_of(draws[1])
            xs = split_column(split_x, size[0])
            values[:, xs:] = right[:, xs:]
        self.error_texels = error_view.texel_size(self.renderer)
        self._error.upload(values)
        self.error_values = values
        self._error_key, self._error_time = key, now

    def encode(self, texture, draws: list[DrawConfig], split_x: float | None, camera: Camera, mode: str, *,
               error_range: float, screenshot=None, hud=None) -> None:
        """Draw the frame into ``texture``; ``screenshot(texture)`` runs after the scene and before the HUD."""
        w, h = texture.size[:2]
        device = self.device
        if self._depth is None or self._depth.size[:2] != (w, h):
            self._depth = device.create_texture(
                label="window:depth", size=(w, h, 1), format=DEPTH_FORMAT, usage="RENDER_ATTACHMENT"
            )
        view = texture.create_view()
        scene_mode = "cost" if mode == "cost" else "color"
        passes = scene_passes(draws, split_x, w, h)
        timer = self.timer
        if timer:
            timer.begin_frame()
        # One submit per scene pass: each pass writes the renderer's frame/params uniforms first.
        for i, (draw, scissor) in enumerate(passes):
            encoder = device.create_command_encoder(label="window")
            writes = timer.writes(i == 0, i == len(passes) - 1) if timer else None
            self.renderer.encode(
                encoder, [view], self._depth.create_view(), (self.format,), draw, camera, (w, h),
                scene_mode, clear=(i == 0), scissor=scissor, timestamp_writes=writes,
            )
            if timer and i == len(passes) - 1:
                timer.encode_resolve(encoder)
            device.queue.submit([encoder.finish()])
        if timer:
            timer.after_submit()
        encoder = device.create_command_encoder(label="window:overlay")
        if mode == "error" and self._error is not None:
            self._error.encode(encoder, view, (0, 0, w, h), error_range)
        if screenshot is not None:  # the scene without the HUD
            device.queue.submit([encoder.finish()])
            screenshot(texture)
            encoder = device.create_command_encoder(label="window:hud")
        if hud is not None:
            hud.encode(encoder, view)
        device.queue.submit([encoder.finish()])

    def read(self, texture) -> np.ndarray:
        """The RGB pixels of ``texture`` (a frame of this encoder's format)."""
        w, h = texture.size[:2]
        raw = self.device.queue.read_texture(  # wgpu-py pads the rows to 256 bytes itself
            {"texture": texture, "mip_level": 0, "origin": (0, 0, 0)},
            {"offset": 0, "bytes_per_row": w * 4, "rows_per_image": h},
            (w, h, 1),
        )
        pixels = np.frombuffer(raw, np.uint8).reshape(h, w, 4)
        rgb = pixels[:, :, [2, 1, 0]] if self.format.startswith("bgra") else pixels[:, :, :3]
        return np.ascontiguousarray(rgb)
