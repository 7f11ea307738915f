"""``wgpuviewer max-pyramid``: the command (its options are the shared ones: --out, --suite, --backend, --quiet)."""

from __future__ import annotations

from wgpuviewer.lab.harness.study import StudyCommand


class MaxPyramid(StudyCommand):
    """No options of its own: the suite decides the maps, angles and sweep (``run.SUITES``)."""


STUDY = MaxPyramid(
    "max-pyramid", "the max MIP pyramid (Romanyuk & Dudnyk 2018): maxmip and quadmax against steep, POM and relief at "
    "equal error and equal SIMD-tile fetches, steps per pyramid level, the early exit (results.csv, levels.csv, "
    "sweep.csv, report.md)",
    "output folder (results.csv, levels.csv, sweep.csv, report.md, pictures)",
    "smoke: two 32x32 maps, two angles, a 16x8 frame; full: seven 256x256 maps (flat-area and noisy), 0-89 degrees, "
    "a 64x32 frame, 2-1024 layers")
