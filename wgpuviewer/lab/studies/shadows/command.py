"""``wgpuviewer shadows``: the command's options."""

from __future__ import annotations

from pathlib import Path

from wgpuviewer.core.cli import comma_list, comma_numbers
from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.harness.study import add_measurement_options


class Shadows:
    name = "shadows"
    help = ("self-shadowing of every ray-search technique against the float64 reference: wrong hard-shadow states, "
            "soft-shadow difference, shadow-ray fetches (results.csv, report.md, shadows.png)")

    def add_arguments(self, parser) -> None:
        add_measurement_options(parser, "output folder (results.csv, report.md, shadows.png)",
                                "smoke: two small maps, two techniques, 30 and 60 degrees; full: the benchmark's maps, "
                                "every ray-search technique, 30-80 degrees")
        parser.add_argument("--heightmaps", help="comma-separated builtins and/or scikit-image brick,grass,gravel")
        parser.add_argument("--techniques", help="comma-separated ray-search techniques (default: the suite's)")
        parser.add_argument("--elevations", help="comma-separated light elevations above the surface, degrees "
                                                 "(above 0, at most 90)")

    def options(self, args) -> dict:
        """``run.run``'s keyword arguments, each option checked."""
        from wgpuviewer.lab.bench.run import check_heightmaps
        from wgpuviewer.relief.accuracy import shadowing_techniques
        from wgpuviewer.techniques import get_technique

        elevations = comma_numbers(args.elevations, "--elevations", "30,80")
        if elevations is not None and not all(0.0 < e <= 90.0 for e in elevations):
            raise UserError(f"--elevations {args.elevations!r}: expected degrees above 0 and at most 90")
        heightmaps = comma_list(args.heightmaps, "--heightmaps")
        check_heightmaps(heightmaps or [])
        techniques = comma_list(args.techniques, "--techniques")
        if techniques is not None:
            techniques = [get_technique(t, "--techniques").name for t in techniques]
            allowed = shadowing_techniques()
            other = [t for t in techniques if t not in allowed]
            if other:
                raise UserError(f"--techniques: {', '.join(other)} cast no shadow of their own (no search along the "
                                f"ray); expected some of {', '.join(allowed)}")
        return {"suite_name": args.suite, "heightmaps": heightmaps, "techniques": techniques,
                "elevations": elevations, "backend": args.backend, "progress": not args.quiet,
                "command": args.command_line}

    def run(self, options: dict, out: Path) -> int:
        from .run import run

        run(out=out, **options)
        print(out / "report.md")
        return 0


STUDY = Shadows()
