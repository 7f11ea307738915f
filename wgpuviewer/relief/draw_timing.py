"""GPU frame times of several draws side by side (round robin) in one renderer: the benchmark's and the studies'
timer of draws, on ``wgpuviewer.core.pass_timing``.

Each frame is one render pass of the full-screen view into a colour target (the window's path, ``fs_color``).
Configurations take turns frame by frame, so drift (clocks, other load) hits all of them alike. With the
``timestamp-query`` feature, the pass's begin and end timestamps give its GPU time, and one round (a frame of
every draw, each with its own uniform buffer: the renderer keeps one per draw configuration) is one submit;
without it, the wall time from submit to completion of each frame, net of an empty pass, is used instead.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import wgpu

from wgpuviewer.core.pass_timing import time_passes

from .renderer import DrawConfig, Renderer
from .targets import COLOR_FORMAT, DEPTH_FORMAT


@dataclass
class Timing:
    median_ms: float
    frames_ms: np.ndarray


@dataclass
class TimingRun:
    timer: str  # "timestamp" or "wall-net" (core.pass_timing)
    results: list[Timing]
    #: Sum of the timed GPU intervals / wall time of the whole run (<= 1 when the timestamp unit is
    #: right; a value far above 1 would mean the timestamps are not nanoseconds).
    busy_fraction: float
    submits: int = 0  # command buffers submitted (compile round and warm-up included)
    readbacks: int = 0  # buffers read back


def time_draws(renderer: Renderer, draws: list[DrawConfig], size: tuple[int, int],
               frames: int, warmup: int, progress=None, mode: str = "color") -> TimingRun:
    """Median GPU ms per frame of each of ``draws``, drawn round robin; ``mode`` as ``Renderer.encode``'s (e.g.
    "albedo": the filtered albedo lookup alone, no shading). The first untimed round compiles the pipelines and
    builds the maps."""
    device = renderer.gpu.device
    w, h = size
    targets = [device.create_texture(label=f"timing:{fmt}", size=(w, h, 1), format=fmt,
                                     usage=wgpu.TextureUsage.RENDER_ATTACHMENT) for fmt in (COLOR_FORMAT, DEPTH_FORMAT)]
    color_view, depth_view = (t.create_view() for t in targets)
    camera = renderer.scene.camera

    def recorder(draw: DrawConfig):
        def record(encoder, writes):
            renderer.encode(encoder, [color_view], depth_view, (COLOR_FORMAT,), draw, camera, size, mode,
                            timestamp_writes=writes)
        return record

    start = time.perf_counter()
    timings = time_passes(device, [recorder(d) for d in draws], frames, warmup=warmup + 1,
                          timestamps="timestamp-query" in renderer.gpu.features, batched=True, progress=progress)
    wall_ms = (time.perf_counter() - start) * 1e3
    results = [Timing(float(np.median(ms)), ms) for ms in timings.samples_ms]
    busy = sum(float(r.frames_ms.sum()) for r in results) / max(wall_ms, 1e-9)
    return TimingRun(timings.timer, results, busy, timings.submits, timings.readbacks)
