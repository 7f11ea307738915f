"""Self-shadowing measured: per ray-search technique, light elevation and height map, how often the hard shadow
through the technique's own ``trace`` is wrong against the float64 reference (``relief.reference.shadow``), how far
the soft estimate is from its dense reference, and what the shadow rays cost in depth fetches, mean and SIMD-tile
(``wgpuviewer shadows``; docs/shadows.md publishes a full run).

- ``command``: the command and its options (``STUDY``);
- ``run``: the suites, the measurement, results.csv, report.md and the picture.

May import ``core``, ``harness``, ``relief``, the scene modules and ``bench`` (its height maps); no other study.
"""

from .command import STUDY

__all__ = ["STUDY"]
