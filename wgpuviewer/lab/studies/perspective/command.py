"""``wgpuviewer perspective``: the command (the suite is its only option beside the shared ones)."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.lab.harness.study import add_measurement_options


class Perspective:
    name = "perspective"
    help = ("perspective-correct texturing study (Romanyuk & Dudnyk): speed and float error of Heckbert's direct, "
            "incremental and parallel forms")

    def add_arguments(self, parser) -> None:
        add_measurement_options(parser, "output folder (results.csv, report.md, *.png)",
                                "full: every sweep, 4K frames (minutes on a software adapter); smoke: seconds, for CI")

    def options(self, args) -> dict:
        """``run.run``'s keyword arguments (argparse has checked the suite); numba is there for the compiled loops."""
        from .compiled import numba_module

        numba_module()
        return {"suite_name": args.suite, "backend": args.backend, "progress": not args.quiet,
                "command": args.command_line}

    def run(self, options: dict, out: Path) -> int:
        from .run import run

        run(out=out, **options)
        print(out / "report.md")
        return 0


STUDY = Perspective()
