"""``wgpuviewer accuracy``: the command's options (``--heightmaps``, ``--texels``, ``--rays``, ``--height-scale``
besides every measuring command's ``--out``, ``--suite``, ``--backend``, ``--quiet``), each checked before a file
is made or the GPU starts."""

from __future__ import annotations

import math

from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.harness.study import StudyCommand

DEFAULT_HEIGHTMAPS = ("bricks", "bumps", "checker")


class Accuracy(StudyCommand):
    def add_options(self, parser) -> None:
        parser.add_argument("--heightmaps", nargs="+", default=list(DEFAULT_HEIGHTMAPS), metavar="NAME",
                            help=f"builtin height maps to measure on (default: {' '.join(DEFAULT_HEIGHTMAPS)})")
        parser.add_argument("--texels", type=int, default=256, help="map size in texels, square (default %(default)s)")
        parser.add_argument("--rays", type=int, default=4096,
                            help="random rays per map and angle (default %(default)s)")
        parser.add_argument("--height-scale", type=float, default=0.05,
                            help="relief depth in UV units (default %(default)s)")

    def options(self, args) -> dict:
        """``run.run``'s keyword arguments, each option checked."""
        from wgpuviewer.relief.accuracy import MAX_RAYS
        from wgpuviewer.textures import BUILTINS, MAX_BUILTIN_SIZE

        for name in args.heightmaps:
            if name not in BUILTINS:
                raise UserError(f"--heightmaps: unknown builtin {name!r}; expected some of {', '.join(BUILTINS)}")
        twice = sorted({name for name in args.heightmaps if args.heightmaps.count(name) > 1})
        if twice:
            raise UserError(f"--heightmaps: {', '.join(twice)} given twice; name each map once")
        if not 1 <= args.texels <= MAX_BUILTIN_SIZE:
            raise UserError(f"--texels {args.texels}: expected 1 to {MAX_BUILTIN_SIZE} texels")
        if not 1 <= args.rays <= MAX_RAYS:
            raise UserError(f"--rays {args.rays}: expected 1 to {MAX_RAYS} rays")
        if not (math.isfinite(args.height_scale) and 0 < args.height_scale <= 1):
            raise UserError(f"--height-scale {args.height_scale}: expected a relief depth in (0, 1] UV units")
        return {**self.shared_options(args), "heightmaps": tuple(args.heightmaps), "texels": args.texels,
                "rays": args.rays, "height_scale": args.height_scale}


STUDY = Accuracy(
    "accuracy", "probe each ray-search technique against the float64 reference: UV error, fetches, capped share, "
    "self-shadowing (results.csv, shadows.csv, report.md)",
    "output folder (results.csv, shadows.csv, report.md)",
    "smoke: 30 and 80 degrees, one light elevation (45); full: nine angles from 0 to 89.9 degrees, four light "
    "elevations")
