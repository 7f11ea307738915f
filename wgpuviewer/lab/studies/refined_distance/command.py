"""``wgpuviewer refined-distance``: the command's options."""

from __future__ import annotations

from wgpuviewer.core.commands import comma_list
from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.harness.study import StudyCommand, numbers_within

from . import reliefs

#: The parts ``--only`` can pick.
ONLY = ("bounded",)
#: The steepest view angle at the frame centre (the benchmark's views look past the horizon at 90).
MAX_ANGLE = 89.0


class RefinedDistance(StudyCommand):
    def add_options(self, parser) -> None:
        parser.add_argument("--heightmaps", help="comma-separated: builtins, scikit-image brick,grass,gravel and/or "
                                                 "the generated " + ",".join(reliefs.NAMES))
        parser.add_argument("--angles", help=f"comma-separated view angles at the frame centre, degrees (0 to "
                                             f"{MAX_ANGLE:g})")
        parser.add_argument("--only", choices=ONLY, help="bounded: only the paper's worked example and the "
                            "exact-visibility bound (example.csv, bounded.csv, bounded_maps.csv, worked_example.png, "
                            "report.md)")

    def options(self, args) -> dict:
        """``run.run``'s keyword arguments, each option checked."""
        from wgpuviewer.lab.bench.run import check_heightmaps

        angles = numbers_within(args.angles, "--angles", "45,89", 0.0, MAX_ANGLE)
        heightmaps = comma_list(args.heightmaps, "--heightmaps")
        try:
            check_heightmaps([h for h in heightmaps or [] if h not in reliefs.NAMES])
        except UserError as e:
            raise UserError(f"{e}, {', '.join(reliefs.NAMES)}") from None
        return {**self.shared_options(args), "heightmaps": heightmaps, "angles": angles, "only": args.only or ""}


STUDY = RefinedDistance(
    "refined-distance", "fetches of the distance tracer on every distance-map variant (Romanyuk et al. 2017, refined "
    "distance map; its visibility condition off and on), Donnelly's fixed budgets, memory and build time of every map "
    "format (results.csv, donnelly.csv, formats.csv, format_costs.csv, report.md)",
    "output folder (results.csv, report.md)",
    "smoke: two small maps, two angles; full: the benchmark's real maps, its builtins, the generated plate and "
    "grille, 0-89 degrees; both also rebuild the paper's worked example and bound the refined map with an "
    "exact-visibility map on their own small maps, whatever --heightmaps says (full: 64x64 crops of the photographs, "
    "the builtins, plate and grille; bounded.csv, bounded_maps.csv)")
