"""The render scale: the scene drawn at a fraction of the window's size and stretched over it (``Upscaler``,
``wgsl/entry/upscale.wgsl``), the HUD drawn over that at full resolution; and its automatic choice (``AutoScale``),
which on a software adapter holds about ``TARGET_FPS`` frames per second.

The setting (``Settings.render_scale``, the U key) is ``auto`` or one of ``SCALES``. ``auto`` is the chooser's in an
interactive run on a software adapter, and 1 otherwise (a hardware adapter; a scripted run, so screenshots and the
golden images are the full-resolution ones).

May import: ``wgpuviewer.core`` (the GPU helpers, the struct generator, the WGSL composer).
"""

from __future__ import annotations

import wgpu

from wgpuviewer.core.gpu import fullscreen_pipeline
from wgpuviewer.core.structs import Struct
from wgpuviewer.core.wgsl import compose

#: The fixed scales, largest first (the U key steps through ``CHOICES``: auto, then these).
SCALES = (1.0, 0.75, 0.5, 0.35, 0.25)
CHOICES = ("auto", *(f"{s:g}" for s in SCALES))
#: Frames per second the automatic choice holds.
TARGET_FPS = 15.0
#: A larger scale is taken only when its predicted rate clears the target by this factor (no back and forth).
RAISE_MARGIN = 1.4
#: The automatic choice judges the frames of at least this many seconds (and frames) at a time.
WINDOW_SECONDS, WINDOW_FRAMES = 1.0, 4
#: Frames longer than this (a shader compiled for a new technique) say nothing about the scene's cost.
OUTLIER_SECONDS = 4.0

UPSCALE = Struct("Upscale", [("target_size", "vec4f")])  # xy: the window's texture size in pixels


def scaled_size(size: tuple[int, int], scale: float) -> tuple[int, int]:
    """The scene's texture size at ``scale`` of a window of ``size`` (at least 1 x 1)."""
    return max(1, round(size[0] * scale)), max(1, round(size[1] * scale))


def next_choice(choice: str) -> str:
    return CHOICES[(CHOICES.index(choice) + 1) % len(CHOICES)]


class AutoScale:
    """The largest of ``SCALES`` whose predicted frame rate holds ``TARGET_FPS``: each window of frames measures the
    rate at the scale in use and predicts it at the others from the pixel count (a scene's cost grows with its
    pixels: the time at scale s' is the time at s times (s'/s)^2)."""

    def __init__(self, scale: float = 1.0):
        self.scale = scale
        self.fps: float | None = None  # the last window's rate, measured at the scale ``measured_at``
        self.measured_at = scale
        self._seconds, self._frames = 0.0, 0

    def add(self, seconds: float) -> bool:
        """One frame took ``seconds``; True when the scale changed."""
        if seconds <= 0.0 or seconds > OUTLIER_SECONDS:
            return False
        self._seconds += seconds
        self._frames += 1
        if self._seconds < WINDOW_SECONDS or self._frames < WINDOW_FRAMES:
            return False
        self.fps, self.measured_at = self._frames / self._seconds, self.scale
        self._seconds, self._frames = 0.0, 0
        chosen = self.choose(self.fps)
        changed = chosen != self.scale
        self.scale = chosen
        return changed

    def choose(self, fps: float) -> float:
        """The scale for a measured ``fps`` at the current one."""
        def predicted(s: float) -> float:
            return fps * (self.scale / s) ** 2

        for s in SCALES:
            needed = TARGET_FPS * (RAISE_MARGIN if s > self.scale else 1.0)
            if predicted(s) >= needed:
                return s
        return SCALES[-1]


class Upscaler:
    """The scene's texture at the render scale, and the pass that stretches it over the window's texture."""

    def __init__(self, device: wgpu.GPUDevice, format: str):
        self.device, self.format = device, format
        entries = [
            {"binding": 0, "visibility": wgpu.ShaderStage.FRAGMENT, "texture": {"sample_type": "float"}},
            {"binding": 1, "visibility": wgpu.ShaderStage.FRAGMENT, "sampler": {"type": "filtering"}},
            {"binding": 2, "visibility": wgpu.ShaderStage.FRAGMENT, "buffer": {"type": "uniform"}},
        ]
        code = compose(UPSCALE.generated(), "entry/upscale.wgsl").code
        self.layout, self.pipeline = fullscreen_pipeline(device, "upscale", code, entries, format)
        self.sampler = device.create_sampler(label="upscale", mag_filter="linear", min_filter="linear")
        self.uniform = device.create_buffer(label="upscale", size=UPSCALE.size,
                                            usage=wgpu.BufferUsage.UNIFORM | wgpu.BufferUsage.COPY_DST)
        self.texture = None
        self.group = None

    def frame(self, size: tuple[int, int]) -> wgpu.GPUTexture:
        """The texture to draw the scene into, ``size`` (the scaled size)."""
        if self.texture is None or self.texture.size[:2] != size:
            self.texture = self.device.create_texture(
                label="window:scaled scene", size=(*size, 1), format=self.format,
                usage=wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.COPY_SRC
                | wgpu.TextureUsage.TEXTURE_BINDING)
            self.group = self.device.create_bind_group(layout=self.layout, entries=[
                {"binding": 0, "resource": self.texture.create_view()}, {"binding": 1, "resource": self.sampler},
                {"binding": 2, "resource": {"buffer": self.uniform}}])
        return self.texture

    def encode(self, encoder, target) -> None:
        """Stretch the scene's texture over ``target`` (the window's texture)."""
        w, h = target.size[:2]
        self.device.queue.write_buffer(self.uniform, 0, UPSCALE.pack({"target_size": (w, h, 0.0, 0.0)}))
        rpass = encoder.begin_render_pass(label="upscale", color_attachments=[
            {"view": target.create_view(), "load_op": "clear", "store_op": "store", "clear_value": (0, 0, 0, 1)}])
        rpass.set_pipeline(self.pipeline)
        rpass.set_bind_group(0, self.group)
        rpass.draw(3)
        rpass.end()
