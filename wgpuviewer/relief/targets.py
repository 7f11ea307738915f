"""The offscreen frame: its render targets (one list, ``DATA_OUT``, gives fs_data's outputs and their formats), what
it costs, the sizes an adapter can make and read back (``check_frame_size``), and the read-back into an
``OffscreenImage``.

A frame too large is a ``FrameError``: a UserError whose message names the size as the caller's setting does
(``size_name``: "render size", the API's ``size``), and which another caller words with its own name
(``FrameError.named``: the CLI's ``--size``).
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass

import numpy as np
import wgpu

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import Gpu, allocating, format_bytes
from wgpuviewer.core.structs import FragmentOutputs
from wgpuviewer.core.wgsl import Generated

COLOR_FORMAT = "rgba8unorm-srgb"  # offscreen colour: shaders write linear, PNGs get sRGB bytes
DATA_FORMAT = "rgba32uint"  # offscreen raw trace data (float bits): hit u, v, depth, fetches
LAYERS_FORMAT = "r32uint"  # offscreen: depth layers the search used per pixel
FILTER_FORMAT = "rgba32uint"  # offscreen: the filter's texels, depth fetches, hidden | flags << 24, ratio bits
VIEW_DEPTH_FORMAT = "r32uint"  # offscreen: camera depth of the traced hit (float bits)
DEPTH_FORMAT = "depth32float"
#: The targets of an offscreen render, in order: fs_data's outputs (generated into the render module) and their
#: formats. Raw values travel as float bits in 32-bit integer targets: float32 targets are not renderable
#: everywhere (OpenGL ES), 32-bit integer ones are.
DATA_OUT = FragmentOutputs("DataOut", [
    ("color", "vec4f", COLOR_FORMAT),
    ("data", "vec4u", DATA_FORMAT),  # fetches negative: capped
    ("layers", "u32", LAYERS_FORMAT),
    ("filtering", "vec4u", FILTER_FORMAT),
    ("view_depth", "u32", VIEW_DEPTH_FORMAT),
])
OFFSCREEN_FORMATS = DATA_OUT.formats

#: Bytes per pixel of the offscreen targets and the depth attachment.
_PIXEL_BYTES = {"rgba8unorm-srgb": 4, "rgba32uint": 16, "r32uint": 4, "depth32float": 4}
#: What a user can do about a frame too large for the adapter.
SMALLER_FRAME = "use a smaller size"
#: Where a FrameError's message names the size's setting.
_NAME = "{size}"


def hit_depth_outputs(outputs: FragmentOutputs) -> Generated:
    """``outputs``' struct as ``NAMEHitDepth`` with the depth builtin after its targets: the output of the entry
    points of depth_offset materials (``fs_data_hit_depth``), the targets from the same list."""
    lines = outputs.wgsl().rstrip("\n").split("\n")
    name = f"{outputs.name}HitDepth"
    lines[0] = f"struct {name} {{"
    lines.insert(-1, "    @builtin(frag_depth) frag_depth: f32,")
    return Generated(f"<generated: struct {name}>", "\n".join(lines) + "\n")


class FrameError(UserError, ValueError):
    """A frame the adapter cannot make, draw or read back. ``str()`` names the size by ``size_name``;
    ``named(name)`` is the same message naming it otherwise (a caller's own option). A ValueError too: the Python
    API raises it as it is (its ``size``)."""

    def __init__(self, template: str, size_name: str):
        self.template = template  # the message, "{size}" where the size's name goes
        self.size_name = size_name
        super().__init__(self.named(size_name))

    def named(self, name: str) -> str:
        return self.template.replace(_NAME, name)


@dataclass
class OffscreenImage:
    color: np.ndarray  # (H, W, 4) uint8, sRGB; alpha 0 where nothing was drawn
    data: np.ndarray  # (H, W, 4) float32: hit u, hit v, hit depth, fetches (negative: capped)
    layers: np.ndarray | None = None  # (H, W) uint32: depth layers the search used (0: no layers)
    layer_range: tuple[float, float] = (0.0, 1.0)  # the layers mode's grey: (N - lo) / (hi - lo)
    #: (H, W, 4) uint32: texels the filter read, depth fetches of its visibility traces and slopes,
    #: hidden texels | flags << 24 (filters.FLAGS), the derivative source's raw length ratio as float32 bits.
    filter: np.ndarray | None = None
    #: (H, W) float32: camera depth of the traced hit, the distance from the camera along its view axis in scene
    #: units (linear view-space depth, not the depth buffer's reversed-Z value).
    view_depth: np.ndarray | None = None

    @property
    def covered(self) -> np.ndarray:
        return self.color[:, :, 3] > 0


def frame_bytes(size: tuple[int, int]) -> int:
    """GPU memory of an offscreen frame of ``size``: its targets and depth attachment."""
    w, h = size
    return w * h * sum(_PIXEL_BYTES[f] for f in (*OFFSCREEN_FORMATS, DEPTH_FORMAT))


def readback_bytes(w: int, h: int, fmt: str) -> int:
    """Bytes of the buffer a w x h target of ``fmt`` is read back through: rows padded to 256 bytes and the whole
    to 4096, as wgpu's ``read_texture`` makes it."""
    row = -(-w * _PIXEL_BYTES[fmt] // 256) * 256
    return -(-row * h // 4096) * 4096


def check_frame_size(gpu: Gpu, size: tuple[int, int], size_name: str = "render size") -> None:
    """Refuse an offscreen frame of ``size`` the adapter cannot make or read back, before anything is loaded or
    drawn: a side beyond its 2D texture limit, or a target whose read-back buffer is beyond its largest buffer.
    The FrameError names ``size_name`` (the setting the size came from) and the largest frame of that shape that
    fits."""
    w, h = size
    limits = gpu.device.limits
    side = limits["max-texture-dimension-2d"]
    if max(w, h) > side:
        raise FrameError(f"{_NAME} {w}x{h}: larger than this adapter's limit of {side} pixels per side; "
                         f"use at most {side} per side", size_name)
    largest = limits["max-buffer-size"]
    fmt = max(OFFSCREEN_FORMATS, key=lambda f: readback_bytes(w, h, f))
    need = readback_bytes(w, h, fmt)
    if need > largest:
        scale = (largest / need) ** 0.5
        fw, fh = max(1, int(w * scale)), max(1, int(h * scale))
        while readback_bytes(fw, fh, fmt) > largest:  # the row padding: shrink a little more
            fw, fh = max(1, fw - 1 - fw // 100), max(1, fh - 1 - fh // 100)
        raise FrameError(f"{_NAME} {w}x{h}: its {fmt} target is read back through a {format_bytes(need)} "
                         f"buffer, more than this adapter's largest buffer of {format_bytes(largest)}; use at most "
                         f"{fw}x{fh}", size_name)


class OffscreenFrame:
    """The targets of one offscreen frame of ``size`` (OFFSCREEN_FORMATS, in order) and its depth attachment; an
    adapter out of memory for them is a FrameError naming ``size_name``."""

    def __init__(self, gpu: Gpu, size: tuple[int, int], size_name: str):
        self.gpu, self.size, self.size_name = gpu, size, size_name
        device = gpu.device
        w, h = size
        usage = wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.COPY_SRC
        labels = ("color", "data", "layers", "filter", "view_depth")
        with _allocating(gpu, f"{_NAME} {w}x{h}", frame_bytes(size), size_name):
            self.targets = [device.create_texture(label=f"offscreen:{label}", size=(w, h, 1), format=fmt, usage=usage)
                            for label, fmt in zip(labels, OFFSCREEN_FORMATS, strict=True)]
            self.depth = device.create_texture(label="offscreen:depth", size=(w, h, 1), format=DEPTH_FORMAT,
                                               usage=wgpu.TextureUsage.RENDER_ATTACHMENT)

    def views(self) -> tuple[list, object]:
        """(the targets' views, the depth attachment's view)."""
        return [t.create_view() for t in self.targets], self.depth.create_view()

    def read(self, layer_range: tuple[float, float]) -> OffscreenImage:
        """The drawn frame, read back."""
        device = self.gpu.device
        w, h = self.size
        color, data, layers, stats, view_depth = self.targets
        with _allocating(self.gpu, f"reading back {_NAME} {w}x{h}", readback_bytes(w, h, DATA_FORMAT),
                         self.size_name):
            return OffscreenImage(
                color=read_texture(device, color, 4, np.uint8),
                data=read_texture(device, data, 4, np.uint32).view(np.float32),
                layers=read_texture(device, layers, 1, np.uint32)[:, :, 0],
                layer_range=layer_range,
                filter=read_texture(device, stats, 4, np.uint32),
                view_depth=read_texture(device, view_depth, 1, np.uint32)[:, :, 0].view(np.float32),
            )


@contextlib.contextmanager
def _allocating(gpu: Gpu, what: str, nbytes: int, size_name: str):
    """``core.gpu.allocating`` for a frame: the adapter out of memory is a FrameError naming ``size_name``."""
    try:
        with allocating(gpu, what, nbytes, SMALLER_FRAME):
            yield
    except UserError as error:
        raise FrameError(str(error), size_name) from None


def read_texture(device, texture, channels: int, dtype) -> np.ndarray:
    """A 2D texture's base level as an (H, W, channels) array of ``dtype``."""
    w, h = texture.size[:2]
    row = w * channels * np.dtype(dtype).itemsize
    raw = device.queue.read_texture(
        {"texture": texture, "mip_level": 0, "origin": (0, 0, 0)},
        {"offset": 0, "bytes_per_row": row, "rows_per_image": h},
        (w, h, 1),
    )
    return np.frombuffer(raw, dtype).reshape(h, w, channels).copy()
