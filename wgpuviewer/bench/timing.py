"""GPU frame times of several configurations drawn side by side (round robin) in one renderer.

Each frame is one render pass of the full-screen view into a colour target (the window's path,
``fs_color``). Configurations take turns frame by frame, so drift (clocks, other load) hits all of them
alike. With the ``timestamp-query`` feature, the pass's begin and end timestamps give its GPU time, and one
round (a frame of every configuration, each with its own uniform buffer: ``Renderer`` keeps one per draw
configuration) is one submit; without it, the wall time from submit to completion of each frame is used
instead (reported as timer ``cpu-wall``), which needs a submit and a wait per frame.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import wgpu

from wgpuviewer.relief.renderer import COLOR_FORMAT, DEPTH_FORMAT, DrawConfig, Renderer


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
    submits: int = 0  # command buffers submitted (compile round and warm-up included)
    readbacks: int = 0  # buffers read back (all timestamps: one)


def time_configs(renderer: Renderer, configs: list[tuple[str, dict]], size: tuple[int, int],
                 frames: int, warmup: int, progress=None) -> TimingRun:
    """Median GPU ms per frame of each (technique, params) in ``configs``, drawn round robin."""
    gpu = renderer.gpu
    device = gpu.device
    w, h = size
    color = device.create_texture(label="bench:color", size=(w, h, 1), format=COLOR_FORMAT,
                                  usage=wgpu.TextureUsage.RENDER_ATTACHMENT)
    depth = device.create_texture(label="bench:depth", size=(w, h, 1), format=DEPTH_FORMAT,
                                  usage=wgpu.TextureUsage.RENDER_ATTACHMENT)
    color_view, depth_view = color.create_view(), depth.create_view()
    draws = [DrawConfig.of(name, params) for name, params in configs]
    timestamps = "timestamp-query" in gpu.features
    camera = renderer.scene.camera
    queries = []
    if timestamps:
        for i, _ in enumerate(configs):
            queries.append(device.create_query_set(label=f"bench:{i}", type="timestamp", count=2 * frames))
    wall = [[] for _ in configs]
    fence = device.create_buffer(label="bench:fence", size=4, usage=wgpu.BufferUsage.COPY_SRC)

    def wait():
        # Reading a buffer back waits for all submitted work (on_submitted_work_done is broken in
        # wgpu-py 0.32's native backend).
        device.queue.read_buffer(fence)

    def record(encoder, i: int, index: int | None):
        writes = None
        if timestamps and index is not None:
            writes = {"query_set": queries[i], "beginning_of_pass_write_index": 2 * index,
                      "end_of_pass_write_index": 2 * index + 1}
        renderer.encode(encoder, [color_view], depth_view, (COLOR_FORMAT,), draws[i], camera, size,
                        timestamp_writes=writes)

    submits = 0

    def frame_round(index: int | None):
        """One frame of every configuration: one submit with timestamps, else one submit and wait each."""
        nonlocal submits
        if timestamps or index is None:
            encoder = device.create_command_encoder(label="bench")
            for i in range(len(configs)):
                record(encoder, i, index)
            device.queue.submit([encoder.finish()])
            submits += 1
            return
        for i in range(len(configs)):
            encoder = device.create_command_encoder(label="bench")
            record(encoder, i, index)
            start = time.perf_counter()
            device.queue.submit([encoder.finish()])
            wait()
            wall[i].append((time.perf_counter() - start) * 1e3)
            submits += 1

    frame_round(None)  # compile pipelines, build maps, outside the timed frames
    wait()
    for _ in range(warmup):
        frame_round(None)
    wait()
    run_start = time.perf_counter()
    for f in range(frames):
        frame_round(f)
        if progress:
            progress()
    wait()
    run_wall_ms = (time.perf_counter() - run_start) * 1e3

    results = []
    readbacks = 0
    if timestamps:
        # All configurations' timestamps resolved into one buffer (offsets 256-byte aligned), read back once.
        stride = -(-16 * frames // 256) * 256
        resolve = device.create_buffer(size=stride * len(queries),
                                       usage=wgpu.BufferUsage.QUERY_RESOLVE | wgpu.BufferUsage.COPY_SRC)
        encoder = device.create_command_encoder(label="bench:resolve")
        for i, qs in enumerate(queries):
            encoder.resolve_query_set(qs, 0, 2 * frames, resolve, i * stride)
        device.queue.submit([encoder.finish()])
        raw = device.queue.read_buffer(resolve)
        readbacks = 1
        for i in range(len(queries)):
            ticks = np.frombuffer(raw, np.uint64, 2 * frames, i * stride).astype(np.int64)
            ms = (ticks[1::2] - ticks[0::2]).astype(np.float64) / 1e6
            results.append(Timing(float(np.median(ms)), ms))
    else:
        results = [Timing(float(np.median(ms)), np.asarray(ms)) for ms in wall]
    busy = sum(float(r.frames_ms.sum()) for r in results) / max(run_wall_ms, 1e-9)
    return TimingRun("timestamp" if timestamps else "cpu-wall", results, busy, submits, readbacks)
