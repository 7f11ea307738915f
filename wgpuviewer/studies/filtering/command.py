"""``wgpuviewer filtering``: the command's options and how they narrow the suite."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.core.cli import comma_list, comma_numbers, parse_size
from wgpuviewer.harness.study import add_measurement_options


class Filtering:
    name = "filtering"
    help = "texture filters on relief against a supersampled reference (results.csv, report.md, pareto.png, crops)"

    def add_arguments(self, parser) -> None:
        add_measurement_options(parser, "output folder",
                                "full: every filter x derivative source on 150 cases (real GPUs); smoke: 3 cases, "
                                "under 2 minutes on a software adapter")
        parser.add_argument("--size", help="frame WIDTHxHEIGHT (default: the suite's)")
        parser.add_argument("--frames", type=int, help="timed frames per configuration (median)")
        parser.add_argument("--reliefs", help="comma-separated: bricks, step, wall, flat0")
        parser.add_argument("--albedos", help="comma-separated: own, checker, stripes, photo")
        parser.add_argument("--angles", help="comma-separated view angles at the frame centre, degrees (0 to 86)")
        parser.add_argument("--footprints", help="comma-separated texels per pixel at the frame centre, e.g. 1,4")
        parser.add_argument("--filters", help="comma-separated filter names (trilinear, the baseline, always runs)")

    def options(self, args) -> dict:
        """``run.run``'s keyword arguments: the suite narrowed by the options (each checked)."""
        from .suites import resolve_options

        options = resolve_options(
            args.suite, size=parse_size(args.size) if args.size else None, frames=args.frames,
            reliefs=comma_list(args.reliefs, "--reliefs"), albedos=comma_list(args.albedos, "--albedos"),
            angles=comma_numbers(args.angles, "--angles", "0,45,80"),
            footprints=comma_numbers(args.footprints, "--footprints", "1,4"),
            filters=comma_list(args.filters, "--filters"), backend=args.backend, command=args.command_line)
        return {"options": options, "progress": not args.quiet}

    def run(self, options: dict, out: Path) -> int:
        from .run import run

        run(out=out, **options)
        print(out / "report.md")
        return 0


STUDY = Filtering()
