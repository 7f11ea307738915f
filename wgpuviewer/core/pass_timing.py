"""GPU time of passes (compute or render) recorded side by side, round robin.

Each recorder records exactly one pass into the encoder it is given and hands the ``timestamp_writes`` dict it is
given to that pass's ``begin_compute_pass``/``begin_render_pass`` (None when not timing by timestamps). The passes
take turns, round after round, so drift (clocks, other load on a shared machine) hits all of them alike; compare
them by their ratios. With timestamps, ``batched`` records a whole round into one submit (for recorders that do not
depend on each other's queue writes, e.g. draws with their own uniform buffers); all timestamps come back in one
read-back.

Two timers:

- ``timestamp``: the pass's begin and end timestamp queries (needs the ``timestamp-query`` feature);
- ``wall-net``: wall time from submit to completion of each pass, minus the median of an empty compute pass timed
  the same way in the same rounds (the submit and wait overhead). For software adapters: on lavapipe, compute-pass
  timestamps come out 100 times too short once the device has drawn any render pass (and disagree with the wall
  clock for some kernels even before), while the wall clock does not depend on the driver's bookkeeping.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import wgpu

Recorder = Callable[[wgpu.GPUCommandEncoder, dict | None], None]


@dataclass
class Timings:
    timer: str  # "timestamp" or "wall-net"
    samples_ms: list[np.ndarray]  # per recorder, one value per round
    overhead_ms: float = 0.0  # wall-net: the empty pass's median, subtracted from every sample
    submits: int = 0  # command buffers submitted (warm-up included)
    readbacks: int = 0  # buffers read back (waits included)

    @property
    def median_ms(self) -> list[float]:
        return [float(np.median(s)) for s in self.samples_ms]


def _empty_pass(encoder: wgpu.GPUCommandEncoder, timestamp_writes: dict | None = None) -> None:
    encoder.begin_compute_pass(label="timing:empty").end()


def time_passes(device: wgpu.GPUDevice, recorders: Sequence[Recorder], repeats: int, *, warmup: int = 1,
                timestamps: bool = True, batched: bool = False, progress: Callable[[], None] | None = None
                ) -> Timings:
    """GPU ms of each recorder's pass over ``repeats`` rounds (after ``warmup`` untimed rounds).

    ``timestamps``: use timestamp queries (the device must have the ``timestamp-query`` feature); otherwise the
    ``wall-net`` timer. ``batched`` (timestamps only): one submit per round instead of one per pass. ``progress``
    is called after each timed round."""
    if repeats < 1:
        raise ValueError(f"repeats = {repeats}: expected at least 1")
    fence = device.create_buffer(label="timing:fence", size=4, usage=wgpu.BufferUsage.COPY_SRC)
    count = {"submits": 0, "readbacks": 0}

    def wait():
        device.queue.read_buffer(fence)  # returns once all submitted work is done
        count["readbacks"] += 1

    def submit(round_: list[tuple[Recorder, dict | None]]):
        encoder = device.create_command_encoder(label="timing")
        for recorder, writes in round_:
            recorder(encoder, writes)
        device.queue.submit([encoder.finish()])
        count["submits"] += 1

    def run_round(round_: list[tuple[Recorder, dict | None]]):
        if batched and timestamps:
            submit(round_)
        else:
            for item in round_:
                submit([item])

    for _ in range(warmup):
        run_round([(recorder, None) for recorder in recorders])
    wait()
    if not timestamps:
        passes = [*recorders, _empty_pass]
        samples = [[] for _ in passes]
        for _ in range(repeats):
            for i, recorder in enumerate(passes):
                start = time.perf_counter()
                submit([(recorder, None)])
                wait()
                samples[i].append((time.perf_counter() - start) * 1e3)
            if progress:
                progress()
        overhead = float(np.median(samples[-1]))
        return Timings("wall-net", [np.maximum(np.asarray(s) - overhead, 0.0) for s in samples[:-1]], overhead,
                       **count)

    queries = [device.create_query_set(label=f"timing:{i}", type="timestamp", count=2 * repeats)
               for i in range(len(recorders))]
    for r in range(repeats):
        run_round([(recorder, {"query_set": queries[i], "beginning_of_pass_write_index": 2 * r,
                               "end_of_pass_write_index": 2 * r + 1}) for i, recorder in enumerate(recorders)])
        if progress:
            progress()
    # Every recorder's timestamps resolved into one buffer (offsets 256-byte aligned), read back once.
    stride = -(-16 * repeats // 256) * 256
    resolved = device.create_buffer(label="timing:resolve", size=stride * max(len(queries), 1),
                                    usage=wgpu.BufferUsage.QUERY_RESOLVE | wgpu.BufferUsage.COPY_SRC)
    encoder = device.create_command_encoder(label="timing:resolve")
    for i, query_set in enumerate(queries):
        encoder.resolve_query_set(query_set, 0, 2 * repeats, resolved, i * stride)
    device.queue.submit([encoder.finish()])
    raw = device.queue.read_buffer(resolved)
    count["submits"] += 1
    count["readbacks"] += 1
    samples = []
    for i in range(len(queries)):
        ticks = np.frombuffer(raw, np.uint64, 2 * repeats, i * stride).astype(np.int64)
        samples.append((ticks[1::2] - ticks[0::2]).astype(np.float64) / 1e6)  # nanoseconds
    return Timings("timestamp", samples, **count)
