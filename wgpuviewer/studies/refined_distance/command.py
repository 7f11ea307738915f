"""``wgpuviewer refined-distance``: the command's options."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.core.cli import comma_list, comma_numbers
from wgpuviewer.core.errors import UserError
from wgpuviewer.harness.study import add_measurement_options


class RefinedDistance:
    name = "refined-distance"
    help = ("fetches of the distance tracer on every distance-map variant (Romanyuk et al. 2017, refined distance "
            "map), on the benchmark's views (results.csv, report.md)")

    def add_arguments(self, parser) -> None:
        add_measurement_options(parser, "output folder (results.csv, report.md)",
                                "smoke: two small maps, two angles; full: the benchmark's real maps and wall, "
                                "0-80 degrees")
        parser.add_argument("--heightmaps", help="comma-separated: builtins and/or scikit-image brick,grass,gravel")
        parser.add_argument("--angles", help="comma-separated view angles at the frame centre, degrees (0 to 85)")

    def options(self, args) -> dict:
        """``run.run``'s keyword arguments, each option checked."""
        from wgpuviewer.bench.run import check_heightmaps

        angles = comma_numbers(args.angles, "--angles", "45,80")
        if angles is not None and not all(0.0 <= a <= 85.0 for a in angles):
            raise UserError(f"--angles {args.angles!r}: expected degrees from 0 to 85")
        heightmaps = comma_list(args.heightmaps, "--heightmaps")
        check_heightmaps(heightmaps or [])
        return {"suite_name": args.suite, "heightmaps": heightmaps, "angles": angles, "backend": args.backend,
                "progress": not args.quiet, "command": args.command_line}

    def run(self, options: dict, out: Path) -> int:
        from .run import run

        run(out=out, **options)
        print(out / "report.md")
        return 0


STUDY = RefinedDistance()
