"""``wgpuviewer refined-distance``: the command's options."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.core.cli import comma_list, comma_numbers
from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.harness.study import add_measurement_options

from . import reliefs

#: The steepest view angle at the frame centre (the benchmark's views look past the horizon at 90).
MAX_ANGLE = 89.0


class RefinedDistance:
    name = "refined-distance"
    help = ("fetches of the distance tracer on every distance-map variant (Romanyuk et al. 2017, refined distance "
            "map; its visibility condition off and on), Donnelly's fixed budgets, memory and build time of every map "
            "format (results.csv, donnelly.csv, formats.csv, format_costs.csv, report.md)")

    def add_arguments(self, parser) -> None:
        add_measurement_options(parser, "output folder (results.csv, report.md)",
                                "smoke: two small maps, two angles; full: the benchmark's real maps, its builtins, "
                                "the generated plate and grille, 0-89 degrees")
        parser.add_argument("--heightmaps", help="comma-separated: builtins, scikit-image brick,grass,gravel and/or "
                                                 "the generated " + ",".join(reliefs.NAMES))
        parser.add_argument("--angles", help=f"comma-separated view angles at the frame centre, degrees (0 to "
                                             f"{MAX_ANGLE:g})")

    def options(self, args) -> dict:
        """``run.run``'s keyword arguments, each option checked."""
        from wgpuviewer.lab.bench.run import check_heightmaps

        angles = comma_numbers(args.angles, "--angles", "45,89")
        if angles is not None and not all(0.0 <= a <= MAX_ANGLE for a in angles):
            raise UserError(f"--angles {args.angles!r}: expected degrees from 0 to {MAX_ANGLE:g}")
        heightmaps = comma_list(args.heightmaps, "--heightmaps")
        try:
            check_heightmaps([h for h in heightmaps or [] if h not in reliefs.NAMES])
        except UserError as e:
            raise UserError(f"{e}, {', '.join(reliefs.NAMES)}") from None
        return {"suite_name": args.suite, "heightmaps": heightmaps, "angles": angles, "backend": args.backend,
                "progress": not args.quiet, "command": args.command_line}

    def run(self, options: dict, out: Path) -> int:
        from .run import run

        run(out=out, **options)
        print(out / "report.md")
        return 0


STUDY = RefinedDistance()
