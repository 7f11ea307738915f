"""Probe accuracy of every ray-search technique against the float64 exact hit (``wgpuviewer accuracy``): per builtin
height map, view angle and setting (each ray-search technique's ``accuracy_settings``), the UV error of the GPU
probe's hit (mean, p95, max), the fetches per ray and the capped share; and each shadowing technique's
self-shadowing per light elevation. docs/accuracy.md publishes a full run from ``benchmarks/accuracy``.

The measurement is the product's (``relief.accuracy.run`` and ``shadow_run``, the same the tests and
``wgpuviewer.accuracy.measure`` use); this folder gives it a command, results files and a report.

- ``command``: the command and its options (``STUDY``);
- ``run``: the suites, the measurement, results.csv, shadows.csv and report.md;
- ``report``: the tables, made from the CSV rows, for report.md and the docs;
- ``docs``: docs/accuracy.md's generated blocks (``BLOCKS``).

May import ``core``, ``harness``, ``relief`` and the scene modules (``textures``: the builtin height maps); no other
study.
"""

from .command import STUDY

__all__ = ["STUDY"]
