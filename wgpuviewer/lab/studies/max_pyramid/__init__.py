"""The max MIP pyramid (Romanyuk & Dudnyk 2018) measured: the ``maxmip`` walk (and ``quadmax``) against the linear
searches (steep, POM, relief) on reliefs with large flat areas and noisy ones, 0-89°, at equal error (p95 and max
against the float64 exact hit) and at equal SIMD-tile fetches; the per-level step statistics the paper asserts, its
early exit, and a Fig. 3-style example pyramid (``wgpuviewer max-pyramid``; benchmarks/max_pyramid publishes a run).

- ``command``: the command and its options (``STUDY``);
- ``reliefs``: the height maps and their classes (the generated plates, the DEM);
- ``twin``: an instrumented float64 numpy twin of ``wgsl/common/maxmip_walk.wgsl`` (same steps, same fetch counts)
  and its per-level statistics;
- ``compare``: equal error and equal cost on a linear search's cost-error curve (log-log interpolation);
- ``tables``: results.csv, levels.csv, sweep.csv;
- ``run``: the suites and the measurement; ``report``: report.md; ``figures``: the pictures;
- ``docs``: docs/max-pyramid.md's generated blocks.

May import ``core``, ``harness``, ``relief``, the scene modules, ``maptools`` and ``bench`` (the benchmark's views
and height maps); no other study.
"""

from .command import STUDY

__all__ = ["STUDY"]
