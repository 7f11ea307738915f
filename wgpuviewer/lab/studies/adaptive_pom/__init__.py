"""Adaptive POM against POM at equal error (the thesis' question): per height map and view angle, the p95, p99 and
max UV error of ``pom`` over a sweep of layer counts and of ``pom_adaptive`` over Nmin x Nmax and its angle-only
variant, against SIMD-tile depth fetches, on the probe (the renderer's WGSL search) against the float64 exact first
hit (``wgpuviewer adaptive-pom``; docs/benchmarks.md publishes a full run).

- ``command``: the command (``STUDY``);
- ``measure``: the suites, the configurations, the measurement; ``run``: the whole run;
- ``compare``: POM's cost at an adaptive configuration's error, interpolated along POM's curve, with a bootstrap
  interval per map (comparison.csv);
- ``report``: report.md and curves.png; ``docs``: docs/benchmarks.md's block.

May import ``core``, ``harness``, ``relief``, the scene modules and ``bench`` (its height maps); no other study.
"""

from .command import STUDY

__all__ = ["STUDY"]
