"""``wgpuviewer perspective``: the command (the suite is its only option beside the shared ones)."""

from __future__ import annotations

from wgpuviewer.lab.harness.study import StudyCommand


class Perspective(StudyCommand):
    def options(self, args) -> dict:
        """``run.run``'s keyword arguments (argparse has checked the suite); numba is there for the compiled loops."""
        from .compiled import numba_module

        numba_module()
        return self.shared_options(args)


STUDY = Perspective(
    "perspective", "perspective-correct texturing study (Romanyuk & Dudnyk): speed and float error of Heckbert's "
    "direct, incremental and parallel forms", "output folder (results.csv, report.md, *.png)",
    "full: every sweep, 4K frames (minutes on a software adapter); smoke: seconds, for CI")
