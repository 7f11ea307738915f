"""GPU frame times of several draws side by side (round robin) in one renderer: the benchmark's and the
studies' timer.

Each frame is one render pass of the full-screen view into a colour target (the window's path,
``fs_color``), recorded and submitted on its own so that a configuration's parameters (written to its
uniform at record time) apply to that frame only. Configurations take turns frame by frame, so
drift (clocks, other load) hits all of them alike. With the ``timestamp-query`` feature, the pass's
begin and end timestamps give its GPU time; without it, the wall time from submit to completion
of each frame is used instead (reported as timer ``cpu-wall``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import wgpu

from .renderer import COLOR_FORMAT, DEPTH_FORMAT, DrawConfig, Renderer


@dataclass
class Timing:
    median_ms: float
    frames_ms: np.ndarray


@dataclass
class TimingRun:
    timer: str  # "timestamp" or "cpu-wall"
    results: list[Timing]
    #: Sum of the timed GPU intervals / wall time of the whole run (<= 1 when the timestamp unit is
    #: right; a value far above 1 would mean the timestamps are not nanoseconds).
    busy_fraction: float


def time_draws(renderer: Renderer, draws: list[DrawConfig], size: tuple[int, int],
               frames: int, warmup: int, progress=None, mode: str = "color") -> TimingRun:
    """Median GPU ms per frame of each of ``draws``, drawn round robin; ``mode`` as ``Renderer.encode``'s (e.g.
    "albedo": the filtered albedo lookup alone, no shading)."""
    gpu = renderer.gpu
    device = gpu.device
    w, h = size
    color = device.create_texture(label="bench:color", size=(w, h, 1), format=COLOR_FORMAT,
                                  usage=wgpu.TextureUsage.RENDER_ATTACHMENT)
    depth = device.create_texture(label="bench:depth", size=(w, h, 1), format=DEPTH_FORMAT,
                                  usage=wgpu.TextureUsage.RENDER_ATTACHMENT)
    color_view, depth_view = color.create_view(), depth.create_view()
    timestamps = "timestamp-query" in gpu.features
    camera = renderer.scene.camera
    queries = []
    if timestamps:
        for i, _ in enumerate(draws):
            queries.append(device.create_query_set(label=f"bench:{i}", type="timestamp", count=2 * frames))
    wall = [[] for _ in draws]
    fence = device.create_buffer(label="bench:fence", size=4, usage=wgpu.BufferUsage.COPY_SRC)

    def wait():
        # Reading a buffer back waits for all submitted work (on_submitted_work_done is broken in
        # wgpu-py 0.32's native backend).
        device.queue.read_buffer(fence)

    def frame(i: int, index: int | None):
        encoder = device.create_command_encoder(label="bench")
        writes = None
        if timestamps and index is not None:
            writes = {"query_set": queries[i], "beginning_of_pass_write_index": 2 * index,
                      "end_of_pass_write_index": 2 * index + 1}
        renderer.encode(encoder, [color_view], depth_view, (COLOR_FORMAT,), draws[i], camera, size, mode,
                        timestamp_writes=writes)
        start = time.perf_counter()
        device.queue.submit([encoder.finish()])
        if not timestamps and index is not None:
            wait()
            wall[i].append((time.perf_counter() - start) * 1e3)

    for i in range(len(draws)):  # compile pipelines, build maps, outside the timed frames
        frame(i, None)
    wait()
    for _ in range(warmup):
        for i in range(len(draws)):
            frame(i, None)
    wait()
    run_start = time.perf_counter()
    for f in range(frames):
        for i in range(len(draws)):
            frame(i, f)
        if progress:
            progress()
    wait()
    run_wall_ms = (time.perf_counter() - run_start) * 1e3

    results = []
    if timestamps:
        resolve = device.create_buffer(size=16 * frames, usage=wgpu.BufferUsage.QUERY_RESOLVE | wgpu.BufferUsage.COPY_SRC)
        for qs in queries:
            encoder = device.create_command_encoder(label="bench:resolve")
            encoder.resolve_query_set(qs, 0, 2 * frames, resolve, 0)
            device.queue.submit([encoder.finish()])
            ticks = np.frombuffer(device.queue.read_buffer(resolve), np.uint64).astype(np.int64)
            ms = (ticks[1::2] - ticks[0::2]).astype(np.float64) / 1e6
            results.append(Timing(float(np.median(ms)), ms))
    else:
        results = [Timing(float(np.median(ms)), np.asarray(ms)) for ms in wall]
    busy = sum(float(r.frames_ms.sum()) for r in results) / max(run_wall_ms, 1e-9)
    return TimingRun("timestamp" if timestamps else "cpu-wall", results, busy)
