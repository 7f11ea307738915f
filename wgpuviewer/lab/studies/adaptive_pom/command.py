"""``wgpuviewer adaptive-pom``: the command (the shared measuring options only; ``run.run`` measures)."""

from __future__ import annotations

from wgpuviewer.lab.harness.study import StudyCommand


class AdaptivePom(StudyCommand):
    """``run.run`` with the options every measuring command has."""


STUDY = AdaptivePom(
    "adaptive-pom", "adaptive POM against POM at equal error: p95/p99/max error against SIMD-tile fetches per map "
    "and angle, an Nmin x Nmax sweep and the angle-only variant (results.csv, comparison.csv, report.md, curves.png)",
    "output folder (results.csv, comparison.csv, report.md, curves.png)",
    "smoke: two maps, two angles, a small grid; full: the benchmark's 12 maps at 0-80 degrees")
