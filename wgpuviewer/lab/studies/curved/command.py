"""``wgpuviewer curved``: the command's options."""

from __future__ import annotations

from wgpuviewer.core.commands import comma_list
from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.harness.study import StudyCommand, numbers_within

#: The largest S/R: beyond it the relief is as deep as a good part of the radius and "displaced surface" loses
#: its sense (at S/R = 1 the floor is the centre).
MAX_RATIO = 0.5
MAX_RAYS = 65536


class Curved(StudyCommand):
    def add_options(self, parser) -> None:
        parser.add_argument("--heightmaps", help="comma-separated: builtins and/or scikit-image brick,grass,gravel")
        parser.add_argument("--angles", help="comma-separated view angles to the normal, degrees (0 to 85)")
        parser.add_argument("--ratios", help=f"comma-separated S/R, height scale over radius (above 0, at most "
                                             f"{MAX_RATIO:g})")
        parser.add_argument("--surfaces", help="comma-separated: sphere, cylinder")
        parser.add_argument("--rays", type=str, help=f"rays per height map, angle and S/R (1 to {MAX_RAYS})")
        parser.add_argument("--techniques", help="comma-separated ray-search techniques traced on the GPU on the same "
                                                 "rays (default parameters), or none: no GPU")

    def options(self, args) -> dict:
        """``run.run``'s keyword arguments, each option checked (no file made; the study starts no GPU)."""
        from wgpuviewer.lab.bench.run import check_heightmaps

        from .geometry import SURFACES

        angles = numbers_within(args.angles, "--angles", "30,80", 0.0, 85.0)
        ratios = numbers_within(args.ratios, "--ratios", "0.001,0.01,0.1", 0.0, MAX_RATIO, "S/R", above_low=True)
        surfaces = comma_list(args.surfaces, "--surfaces")
        for surface in surfaces or []:
            if surface not in SURFACES:
                raise UserError(f"--surfaces: unknown surface {surface!r}; expected some of {', '.join(SURFACES)}")
        rays = None
        if args.rays is not None:
            try:
                rays = int(args.rays)
            except ValueError:
                rays = 0
            if not 1 <= rays <= MAX_RAYS:
                raise UserError(f"--rays {args.rays!r}: expected a whole number from 1 to {MAX_RAYS}")
        heightmaps = comma_list(args.heightmaps, "--heightmaps")
        check_heightmaps(heightmaps or [])
        return {**self.shared_options(args), "heightmaps": heightmaps, "angles": angles, "ratios": ratios,
                "surfaces": surfaces, "rays": rays, "techniques": _techniques(args.techniques)}


def _techniques(text: str | None) -> tuple[str, ...] | None:
    """--techniques as names of ray-search techniques; () for "none"; None when not given (the suite's)."""
    from wgpuviewer.techniques import TECHNIQUES

    names = comma_list(text, "--techniques")
    if names is None or names == ["none"]:
        return None if names is None else ()
    tracing = [name for name, t in TECHNIQUES.items() if t.ray_search]
    for name in names:
        if name not in tracing:
            raise UserError(f"--techniques: {name!r} is no ray-search technique; expected some of "
                            f"{', '.join(tracing)}, or none")
    return tuple(names)


STUDY = Curved(
    "curved", "the tangent-plane trace against the exact hit on a sphere or cylinder of radius R, float64, as a "
    "function of S/R and the view angle, and techniques against the same truth (results.csv, report.md, plots)",
    "output folder (results.csv, report.md, *.png)",
    "smoke: one small map, two angles, two S/R, pom (seconds); full: real and hard maps at 128x128, 0-85 degrees, "
    "S/R 1e-3 to 0.2, sphere and cylinder, pom and maxmip")
