"""The benchmark's trace data of one view: every configuration's raw trace target (hit uv, hit depth, fetches) and
coverage, rendered in batches into array textures: one submit and two read-backs (colour for the coverage, data)
per batch, where ``Renderer.render`` takes a submit and three read-backs per configuration.

Draws recorded into one submit share the renderer's frame uniform (camera, mode): they are all of the same view.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import wgpu

from wgpuviewer.relief.renderer import DrawConfig, Renderer
from wgpuviewer.relief.targets import COLOR_FORMAT, DATA_FORMAT, DEPTH_FORMAT, LAYERS_FORMAT

#: Most bytes one batch reads back (colour + data targets of its configurations).
MAX_BATCH_BYTES = 256 << 20


@dataclass
class Capture:
    covered: np.ndarray  # (H, W) bool: the fragment was drawn (not discarded)
    data: np.ndarray  # (H, W, 4) float32: hit u, hit v, hit depth, fetches (negative: capped)


@dataclass
class CaptureRun:
    captures: list[Capture]
    submits: int
    readbacks: int


def _read_layers(device, texture, n: int, channels: int, dtype) -> np.ndarray:
    w, h = texture.size[:2]
    row = w * channels * np.dtype(dtype).itemsize
    raw = device.queue.read_texture({"texture": texture, "mip_level": 0, "origin": (0, 0, 0)},
                                    {"offset": 0, "bytes_per_row": row, "rows_per_image": h}, (w, h, n))
    return np.frombuffer(raw, dtype).reshape(n, h, w, channels)


def capture(renderer: Renderer, draws: list[DrawConfig], size: tuple[int, int],
            max_bytes: int = MAX_BATCH_BYTES) -> CaptureRun:
    """Coverage and raw trace data of each draw in ``draws`` (the renderer's scene camera), in batches."""
    device = renderer.gpu.device
    w, h = size
    camera = renderer.scene.camera
    batch = max(1, min(len(draws), max_bytes // max(w * h * 20, 1)))
    usage = wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.COPY_SRC
    depth = device.create_texture(label="capture:depth", size=(w, h, 1), format=DEPTH_FORMAT,
                                  usage=wgpu.TextureUsage.RENDER_ATTACHMENT)
    depth_view = depth.create_view()
    out, submits, readbacks = [], 0, 0
    for first in range(0, len(draws), batch):
        part = draws[first:first + batch]
        n = len(part)
        color = device.create_texture(label="capture:color", size=(w, h, n), format=COLOR_FORMAT, usage=usage)
        data = device.create_texture(label="capture:data", size=(w, h, n), format=DATA_FORMAT, usage=usage)
        layers = device.create_texture(label="capture:layers", size=(w, h, n), format=LAYERS_FORMAT,
                                       usage=wgpu.TextureUsage.RENDER_ATTACHMENT)
        encoder = device.create_command_encoder(label="capture")
        for i, draw in enumerate(part):
            views = [t.create_view(dimension="2d", base_array_layer=i, array_layer_count=1)
                     for t in (color, data, layers)]
            renderer.encode(encoder, views, depth_view, (COLOR_FORMAT, DATA_FORMAT, LAYERS_FORMAT), draw, camera, size)
        device.queue.submit([encoder.finish()])
        submits += 1
        alpha = _read_layers(device, color, n, 4, np.uint8)[..., 3]
        raw = _read_layers(device, data, n, 4, np.uint32).view(np.float32)
        readbacks += 2
        out += [Capture(alpha[i] > 0, raw[i]) for i in range(n)]
    return CaptureRun(out, submits, readbacks)


def percentile_of_counts(counts: np.ndarray, q: float) -> float:
    """``np.percentile(values, q)`` (linear interpolation) of non-negative integer values given as
    ``np.bincount(values)``: the fetch counts of a frame are integers, and counting them is much faster than
    sorting two million floats. NaN for no values."""
    n = int(counts.sum())
    if n == 0:
        return float("nan")
    rank = q / 100.0 * (n - 1)
    lo = int(np.floor(rank))
    cum = np.cumsum(counts)
    v_lo = int(np.searchsorted(cum, lo + 1))
    v_hi = int(np.searchsorted(cum, min(lo + 2, n)))
    return float(v_lo + (rank - lo) * (v_hi - v_lo))
