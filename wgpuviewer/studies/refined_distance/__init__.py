"""The refined distance map (Romanyuk et al. 2017) measured: the distance tracer's fetches per pixel on every
distance-map variant (the plain map on the cell-min and the sub-cell solid, the paper's single-cone refined map,
sectors, sectors x polar bands), on the benchmark's views, mean and SIMD-tile, with build times and memory
(``wgpuviewer refined-distance``; docs/maps.md publishes a full run).

- ``command``: the command and its options (``STUDY``);
- ``baseline``: the plain map of maptools version 2, the baseline the others are measured against;
- ``tracer``: a float64 numpy twin of ``wgsl/techniques/distance.wgsl`` (same steps, same fetch counts);
- ``run``: the variants, the suites, results.csv and report.md.

May import ``core``, ``harness``, ``relief``, the scene modules, ``maptools`` and ``bench`` (the benchmark's views
and height maps); no other study.
"""

from .command import STUDY

__all__ = ["STUDY"]
