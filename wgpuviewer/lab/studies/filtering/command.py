"""``wgpuviewer filtering``: the command's options and how they narrow the suite."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.core.commands import comma_list, comma_numbers, parse_size
from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.harness.study import add_measurement_options


class Filtering:
    name = "filtering"
    help = "texture filters on relief against a supersampled reference (results.csv, report.md, pareto.png, crops)"

    def add_arguments(self, parser) -> None:
        add_measurement_options(parser, "output folder",
                                "full: every filter x derivative source x tracer on 285 cases (real GPUs); smoke: 3 cases, "
                                "under 2 minutes on a software adapter")
        parser.add_argument("--size", help="frame WIDTHxHEIGHT (default: the suite's)")
        parser.add_argument("--frames", type=int, help="timed frames per configuration (median)")
        parser.add_argument("--reliefs", help="comma-separated: bricks, step, wall, flat0, bumps")
        parser.add_argument("--albedos", help="comma-separated: own, checker, stripes, photo, masked")
        parser.add_argument("--angles", help="comma-separated view angles at the frame centre, degrees (0 to 86)")
        parser.add_argument("--footprints", help="comma-separated texels per pixel at the frame centre, e.g. 1,4")
        parser.add_argument("--filters", help="comma-separated filter names (trilinear, the baseline, always runs)")
        parser.add_argument("--from-csv", metavar="CSV",
                            help="measure nothing: write report.md and the plots from this results.csv (and the "
                                 "run.json beside it) into --out")

    def options(self, args) -> dict:
        """``run.run``'s keyword arguments: the suite narrowed by the options (each checked)."""
        from .suites import resolve_options

        options = resolve_options(
            args.suite, size=parse_size(args.size) if args.size else None, frames=args.frames,
            reliefs=comma_list(args.reliefs, "--reliefs"), albedos=comma_list(args.albedos, "--albedos"),
            angles=comma_numbers(args.angles, "--angles", "0,45,80"),
            footprints=comma_numbers(args.footprints, "--footprints", "1,4"),
            filters=comma_list(args.filters, "--filters"), backend=args.backend, command=args.command_line)
        from_csv = Path(args.from_csv) if args.from_csv else None
        if from_csv is not None and not from_csv.is_file():
            raise UserError(f"--from-csv {from_csv}: no such file; give the results.csv of a filtering run")
        return {"options": options, "progress": not args.quiet, "from_csv": from_csv}

    def run(self, options: dict, out: Path) -> int:
        from .report import rereport
        from .run import run

        if options["from_csv"] is not None:
            rereport(options["from_csv"], out)
        else:
            run(options["options"], out, progress=options["progress"])
        print(out / "report.md")
        return 0


STUDY = Filtering()
