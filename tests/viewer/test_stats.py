"""Frame statistics: FPS current/min/avg/max, reset, GPU times; the heat maps' mean and p95 per half."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.viewer.stats import FrameStats, Summary, half_summaries


def feed(stats: FrameStats, dts, start=100.0) -> float:
    t = start
    stats.tick(t)
    for dt in dts:
        t += dt
        stats.tick(t)
    return t


def test_fps_min_avg_max_and_frame_time():
    stats = FrameStats(window=2, warmup=0)
    assert stats.fps is None and stats.fps_min is None and stats.lines()[0].startswith("FPS -")
    feed(stats, [0.010, 0.020, 0.040])
    assert stats.fps_max == pytest.approx(100.0)
    assert stats.fps_min == pytest.approx(25.0)
    assert stats.fps_avg == pytest.approx(3 / 0.070)
    assert stats.fps == pytest.approx(1 / 0.030)  # smoothed over the last 2 frames
    assert stats.frame_ms == pytest.approx(30.0)
    assert "min 25.0" in stats.lines()[0] and "max 100.0" in stats.lines()[0]


def test_warmup_intervals_and_reset():
    stats = FrameStats(warmup=2)
    feed(stats, [5.0, 3.0, 0.010, 0.010])  # shader compiles in the first frames do not count
    assert stats.frames == 2 and stats.fps_min == pytest.approx(100.0)
    stats.add_gpu_time(1.5)
    stats.reset()
    assert stats.frames == 0 and stats.fps_avg is None and stats.gpu_time_ms is None
    feed(stats, [1.0, 1.0, 0.5])
    assert stats.frames == 1 and stats.fps_max == pytest.approx(2.0)


def test_gpu_time_is_the_median_of_recent_frames():
    stats = FrameStats(window=5)
    for ms in (1.0, 1.2, 50.0, 1.1):
        stats.add_gpu_time(ms)
    assert stats.gpu_time_ms == pytest.approx(1.15)
    assert "GPU 1.150 ms" in stats.lines()[1]


def test_heat_map_summaries_give_mean_and_p95_of_the_drawn_pixels_of_each_half():
    values = np.array([[0, 1, 2, 10], [-1, 3, -1, 20]], np.float32)  # -1: nothing drawn there
    (whole,) = half_summaries(values, None)
    assert whole.mean == pytest.approx(6.0) and whole.p95 == pytest.approx(np.percentile([0, 1, 2, 10, 3, 20], 95))
    a, b = half_summaries(values, 0.5)  # A: columns 0-1, B: columns 2-3
    assert a == Summary(pytest.approx(4 / 3), pytest.approx(2.8))  # 0, 1, 3: p95 between 1 and 3 at 0.9
    assert b == Summary(pytest.approx(32 / 3), pytest.approx(19.0))  # 2, 10, 20
    assert half_summaries(values, 0.25)[0] == Summary(0.0, 0.0)  # A is column 0: one drawn pixel
    assert half_summaries(np.full((2, 4), -1, np.float32), 0.5) == [None, None]  # nothing drawn: no numbers
