"""``wgpuviewer shadows``: the command's options."""

from __future__ import annotations

from wgpuviewer.core.commands import comma_list
from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.harness.study import StudyCommand, numbers_within


class Shadows(StudyCommand):
    def add_options(self, parser) -> None:
        parser.add_argument("--heightmaps", help="comma-separated builtins and/or scikit-image brick,grass,gravel")
        parser.add_argument("--techniques", help="comma-separated ray-search techniques (default: the suite's)")
        parser.add_argument("--elevations", help="comma-separated light elevations above the surface, degrees "
                                                 "(above 0, at most 90)")

    def options(self, args) -> dict:
        """``run.run``'s keyword arguments, each option checked."""
        from wgpuviewer.lab.bench.run import check_heightmaps
        from wgpuviewer.relief.accuracy import shadowing_techniques
        from wgpuviewer.techniques import get_technique

        elevations = numbers_within(args.elevations, "--elevations", "30,80", 0.0, 90.0, above_low=True)
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
        return {**self.shared_options(args), "heightmaps": heightmaps, "techniques": techniques,
                "elevations": elevations}


STUDY = Shadows(
    "shadows", "self-shadowing of every ray-search technique against the float64 reference: wrong hard-shadow "
    "states, soft-shadow difference, shadow-ray fetches (results.csv, report.md, shadows.png)",
    "output folder (results.csv, report.md, shadows.png)",
    "smoke: two small maps, two techniques, 30 and 60 degrees; full: the benchmark's maps, every ray-search "
    "technique, 30-80 degrees")
