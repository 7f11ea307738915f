"""Frame statistics: FPS current/min/avg/max, reset, GPU times."""

from __future__ import annotations

import pytest

from wgpuviewer.viewer.stats import FrameStats


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
