"""Statistics for the viewer: FPS current/min/avg/max, frame time, GPU time from timestamp queries read back
asynchronously (a few frames late, never stalling the frame that asked), and the mean and 95th percentile of each
A/B half of the cost and error views' heat maps."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
import wgpu


class FrameStats:
    """Frame times fed by ``tick(now)``; min/avg/max since the last ``reset()``.

    ``current`` is smoothed over the last ``window`` frames so the number is readable. The first
    frame after a reset only starts the clock (it would measure the pause before it).
    """

    def __init__(self, window: int = 30, warmup: int = 2):
        self.window = window
        self.warmup = warmup  # intervals ignored after a reset (pipeline builds, first present)
        self.reset()

    def reset(self):
        self._last: float | None = None
        self._skip = self.warmup
        self._recent: deque[float] = deque(maxlen=self.window)
        self.frames = 0
        self.total_time = 0.0
        self.min_dt = float("inf")
        self.max_dt = 0.0
        self.gpu_ms: deque[float] = deque(maxlen=self.window)

    def tick(self, now: float) -> None:
        if self._last is not None:
            dt = now - self._last
            if self._skip > 0:
                self._skip -= 1
            elif dt > 0:
                self._recent.append(dt)
                self.frames += 1
                self.total_time += dt
                self.min_dt = min(self.min_dt, dt)
                self.max_dt = max(self.max_dt, dt)
        self._last = now

    def add_gpu_time(self, ms: float) -> None:
        self.gpu_ms.append(ms)

    @property
    def frame_ms(self) -> float | None:
        return 1000.0 * float(np.mean(self._recent)) if self._recent else None

    @property
    def fps(self) -> float | None:
        return 1.0 / float(np.mean(self._recent)) if self._recent else None

    @property
    def fps_min(self) -> float | None:
        return 1.0 / self.max_dt if self.frames else None

    @property
    def fps_max(self) -> float | None:
        return 1.0 / self.min_dt if self.frames else None

    @property
    def fps_avg(self) -> float | None:
        return self.frames / self.total_time if self.frames and self.total_time > 0 else None

    @property
    def gpu_time_ms(self) -> float | None:
        """Median of the recent GPU times (robust against one slow readback)."""
        return float(np.median(self.gpu_ms)) if self.gpu_ms else None

    def lines(self) -> list[str]:
        def f(x, fmt):
            return "-" if x is None else format(x, fmt)

        out = [
            f"FPS {f(self.fps, '.1f')}  (min {f(self.fps_min, '.1f')}  avg {f(self.fps_avg, '.1f')}  "
            f"max {f(self.fps_max, '.1f')})",
            f"frame {f(self.frame_ms, '.2f')} ms",
        ]
        if self.gpu_ms:
            out[-1] += f"   GPU {f(self.gpu_time_ms, '.3f')} ms"
        return out


@dataclass(frozen=True)
class Summary:
    """What a heat map shows over one half of the screen: the mean and 95th percentile of its drawn pixels."""

    mean: float
    p95: float


def split_column(split_x: float, width: int) -> int:
    """The first column of half B in a map ``width`` wide split at fraction ``split_x`` (as the error view splits)."""
    return int(round(split_x * width))


def half_summaries(values: np.ndarray, split_x: float | None) -> list[Summary | None]:
    """``Summary`` of each half of a heat map (``values`` (H, W), negative where nothing was drawn): one for the whole
    map unsplit, [A, B] split at fraction ``split_x``; None for a half where nothing was drawn."""
    halves = [values] if split_x is None else np.split(values, [split_column(split_x, values.shape[1])], axis=1)
    out = []
    for half in halves:
        drawn = half[half >= 0]
        out.append(Summary(float(drawn.mean()), float(np.percentile(drawn, 95))) if drawn.size else None)
    return out


#: Bytes between the slots of the resolve buffer: WebGPU's query resolve offset alignment.
RESOLVE_STRIDE = 256


class GpuTimer:
    """GPU time of the scene passes from 'timestamp-query'.

    Each frame takes a free slot of a small ring (2 timestamps each), hands its ``timestamp_writes``
    to the first and last pass, resolves into a buffer and copies that to a mappable one; the map is
    started after submit and collected by a later ``collect()`` once done. When all slots are busy a
    frame simply goes unmeasured, so the CPU never waits for the GPU here.
    """

    def __init__(self, device: wgpu.GPUDevice, slots: int = 4):
        self.device = device
        self.slots = slots
        self.query_set = device.create_query_set(label="gpu-timer", type="timestamp", count=2 * slots)
        # Each slot resolves at its own multiple of 256 bytes (QUERY_RESOLVE_BUFFER_ALIGNMENT).
        self.resolve = device.create_buffer(
            label="gpu-timer:resolve", size=RESOLVE_STRIDE * slots,
            usage=wgpu.BufferUsage.QUERY_RESOLVE | wgpu.BufferUsage.COPY_SRC,
        )
        self.readback = [
            device.create_buffer(
                label=f"gpu-timer:read{i}", size=16, usage=wgpu.BufferUsage.MAP_READ | wgpu.BufferUsage.COPY_DST
            )
            for i in range(slots)
        ]
        self._pending: dict[int, tuple[object, int]] = {}  # slot -> (map promise, age in frames)
        self._current: int | None = None

    @staticmethod
    def available(gpu) -> bool:
        return "timestamp-query" in gpu.features

    def begin_frame(self) -> int | None:
        """Claim a slot for this frame (None: all busy, don't measure)."""
        free = [i for i in range(self.slots) if i not in self._pending]
        self._current = free[0] if free else None
        return self._current

    def writes(self, first: bool, last: bool) -> dict | None:
        """``timestamp_writes`` for a pass: the first pass writes the start, the last the end."""
        if self._current is None or not (first or last):
            return None
        out = {"query_set": self.query_set}
        if first:
            out["beginning_of_pass_write_index"] = 2 * self._current
        if last:
            out["end_of_pass_write_index"] = 2 * self._current + 1
        return out

    def encode_resolve(self, encoder: wgpu.GPUCommandEncoder) -> None:
        if self._current is None:
            return
        i = self._current
        encoder.resolve_query_set(self.query_set, 2 * i, 2, self.resolve, RESOLVE_STRIDE * i)
        encoder.copy_buffer_to_buffer(self.resolve, RESOLVE_STRIDE * i, self.readback[i], 0, 16)

    def after_submit(self) -> None:
        if self._current is None:
            return
        self._pending[self._current] = (self.readback[self._current].map_async("READ"), 0)
        self._current = None

    def collect(self) -> list[float]:
        """GPU times (ms) of the frames whose readback has finished."""
        done = []
        for i, (promise, age) in list(self._pending.items()):
            ready = getattr(promise, "_thread_event", None)
            # Non-blocking check where wgpu-native exposes it; else wait only for old slots (long done).
            if ready is not None and not ready.is_set() and age < 16:
                self._pending[i] = (promise, age + 1)
                continue
            if ready is None and age < 2:
                self._pending[i] = (promise, age + 1)
                continue
            del self._pending[i]
            try:
                promise.sync_wait()
                start, end = np.frombuffer(self.readback[i].read_mapped(), np.uint64)[:2]
            except RuntimeError:
                continue
            finally:
                if self.readback[i].map_state == "mapped":
                    self.readback[i].unmap()
            if end > start:
                done.append((int(end) - int(start)) * 1e-6)  # timestamps are nanoseconds
        return done
