"""``wgpuviewer perspective``: the command (the suite is its only option beside the shared ones)."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.harness.study import add_measurement_options


class Perspective:
    name = "perspective"
    help = ("perspective-correct texturing study (Romanyuk & Dudnyk): speed and float error of Heckbert's direct, "
            "incremental and parallel forms")

    def add_arguments(self, parser) -> None:
        add_measurement_options(parser, "output folder (results.csv, report.md, *.png)",
                                "full: every sweep, 4K frames (minutes on a software adapter); smoke: seconds, for CI")

    def run(self, args) -> int:
        from .run import run

        run(args.suite, Path(args.out), backend=args.backend, progress=not args.quiet, command=args.command_line)
        print(Path(args.out) / "report.md")
        return 0


STUDY = Perspective()
