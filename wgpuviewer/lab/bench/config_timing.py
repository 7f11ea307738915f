"""GPU frame times for the benchmark: (technique, params) configurations timed side by side by the shared timer of
draws, ``wgpuviewer.relief.draw_timing`` (round robin, one submit per round, timestamp queries or wall time)."""

from __future__ import annotations

from wgpuviewer.relief.draw_timing import TimingRun, time_draws
from wgpuviewer.relief.renderer import DrawConfig, Renderer


def time_configs(renderer: Renderer, configs: list[tuple[str, dict]], size: tuple[int, int],
                 frames: int, warmup: int, progress=None) -> TimingRun:
    """Median GPU ms per frame of each (technique, params) in ``configs``, drawn round robin."""
    return time_draws(renderer, [DrawConfig.of(name, params) for name, params in configs], size, frames, warmup,
                      progress)
