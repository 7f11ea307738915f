"""The refined distance map (Romanyuk et al. 2017) measured: the distance tracer's fetches per pixel on every
distance-map variant (the plain map on the cell-min and the sub-cell solid, the paper's single-cone refined map,
sectors, sectors x polar bands; the paper's visibility condition off and on), on the benchmark's views up to 89°
and on generated pits and slots, mean and SIMD-tile; Donnelly's fixed-budget regime beside the exact one; memory
and build time of every map format (``wgpuviewer refined-distance``; benchmarks/refined_distance publishes a run).

- ``command``: the command and its options (``STUDY``);
- ``baseline``: the plain map of maptools version 2, the baseline the others are measured against;
- ``tracer``: a float64 numpy twin of ``wgpuviewer/techniques/distance/distance.wgsl``'s sphere-step / cell-solve loop (same
  steps, same fetch counts);
- ``reliefs``: the generated perforated plate and slot grille;
- ``donnelly``: a float64 model of Donnelly's loop (fixed iterations, trilinear lookups, no finish);
- ``formats``: bytes per texel and build times of the map formats;
- ``run``: the variants, the suites, the CSV files, the picture and report.md.

May import ``core``, ``harness``, ``relief``, the scene modules, ``maptools`` and ``bench`` (the benchmark's views
and height maps); no other study.
"""

from .command import STUDY

__all__ = ["STUDY"]
