"""Where the paper's visibility condition could pay: perforated plates whose holes are wider and deeper than the
study's ``plate`` (``reliefs.plate`` with other diameters and pitches, and height scales up to 0.4, where a hole is
up to 10x deeper than wide). Per plate and view angle, random rays through the numpy twin of the tracer
(``tracer.trace``: fetches to the exact hit) and Donnelly's fixed loop (``donnelly.march``: error at a fixed
budget), with the condition off and on, for the paper's single cone and the product's bins."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wgpuviewer.lab.harness.table import Column, Table

from . import donnelly, reliefs
from .tracer import trace


@dataclass(frozen=True)
class Plate:
    diameter: float  # texels
    pitch: float  # texels
    height_scale: float

    @property
    def name(self) -> str:
        return f"holes {self.diameter:g} every {self.pitch:g}, S {self.height_scale:g}"


#: The plates: the study's own (5 texels every 12), then deeper and wider holes.
PLATES = (Plate(5, 12, 0.05), Plate(5, 12, 0.2), Plate(10, 24, 0.2), Plate(16, 32, 0.2), Plate(16, 32, 0.4))
#: (sectors, bands) of the two maps compared: the paper's single cone and the product's bins.
BINS = ((1, 1), (4, 8))
MAX_ANGLE = 85.0
SLICES = 16

#: pits.csv: per plate x angle x bins x condition, fetches to the exact hit and Donnelly's error at its budget.
TABLE = Table("refined-distance deep pits", (
    Column("plate", str), Column("size", int, "texels per side"), Column("hole_depth", float, "texels"),
    Column("angle", float, "degrees"), Column("bins", str, "sectors x bands"), Column("visibility", str),
    Column("fetches_mean", float, "per ray, the exact tracer (twin)"),
    Column("fetches_holes", float, "per ray entering a hole"),
    Column("budget", int, "Donnelly's fixed iterations"),
    Column("error_p95_holes", float, "texels, Donnelly's loop, rays entering a hole"), Column("rays", int),
))


def measure(size: int, angles, rays: int, budget: int, build, on_plate=lambda rows: None) -> list[dict]:
    """Rows of TABLE for every plate at ``size``². ``build(height, height_scale, **options)`` makes a
    distance_refined volume (the study's cached GPU build); ``on_plate`` hears each plate's rows."""
    from wgpuviewer.relief.accuracy import random_rays
    from wgpuviewer.relief.reference import exact_hit

    out = []
    for plate in PLATES:
        height = reliefs.plate(size, plate.diameter, plate.pitch)
        depth = 1.0 - height.astype(np.float64)
        rows = []
        maps = {(b, vis): build(height, plate.height_scale, sectors=b[0], bands=b[1], max_angle=MAX_ANGLE,
                                visibility=vis)
                for b in BINS for vis in ("off", "on")}
        for angle in angles:
            uv, v = random_rays(rays, angle, seed=round(angle) + 7)
            hole = height[(uv[:, 1] * size).astype(int) % size, (uv[:, 0] * size).astype(int) % size] < 0.5
            exact = exact_hit(depth, uv, v, plate.height_scale)
            for (b, vis), vol in maps.items():
                bins = {"sectors": b[0], "bands": b[1], "max_angle": MAX_ANGLE}
                got = trace(depth, vol, uv, v, plate.height_scale, **bins)
                marched = donnelly.march(vol, uv[hole], v[hole], plate.height_scale, budget, **bins)
                acc = donnelly.accuracy(marched, exact.t[hole], exact.uv[hole], (size, size), v[hole],
                                        plate.height_scale)
                rows.append({"plate": plate.name, "size": size, "hole_depth": plate.height_scale * size,
                             "angle": float(angle), "bins": f"{b[0]} x {b[1]}", "visibility": vis,
                             "fetches_mean": float(got.fetches.mean()),
                             "fetches_holes": float(got.fetches[hole].mean()) if hole.any() else float("nan"),
                             "budget": budget, "error_p95_holes": acc.p95, "rays": rays})
        out += rows
        on_plate(rows)
    return out


def section(rows: list[dict]) -> list[str]:
    """The report's table: per plate and angle, the condition's change of fetches (all rays / rays entering a hole)
    and Donnelly's p95 error off -> on, for the single cone and the product's bins."""
    if not rows:
        return []
    by = {(r["plate"], r["angle"], r["bins"], r["visibility"]): r for r in rows}
    budget = rows[0]["budget"]
    lines = ["### Deeper and wider holes", "",
             f"Random rays ({rows[0]['rays']} per plate and angle) over perforated plates {rows[0]['size']}² "
             f"(`studies/refined_distance/pits.py`): fetches to the exact hit with the condition on vs off (all rays "
             f"/ rays entering a hole), and Donnelly's loop at {budget} iterations: p95 error of the rays entering a "
             "hole, off → on.", "",
             "| plate | hole depth | angle | single cone: fetches on vs off | single cone: Donnelly p95 | "
             "4 x 8 bins: fetches on vs off | 4 x 8 bins: Donnelly p95 |", "|---|---|---|---|---|---|---|"]
    for plate, angle in dict.fromkeys((r["plate"], r["angle"]) for r in rows):
        cells = []
        for b in (f"{s} x {n}" for s, n in BINS):
            off, on = by[(plate, angle, b, "off")], by[(plate, angle, b, "on")]
            cells.append(f"{_pct(on['fetches_mean'], off['fetches_mean'])} / "
                         f"{_pct(on['fetches_holes'], off['fetches_holes'])}")
            cells.append(f"{off['error_p95_holes']:.2f} → {on['error_p95_holes']:.2f}")
        depth = by[(plate, angle, "1 x 1", "off")]["hole_depth"]
        lines.append(f"| {plate} | {depth:g} | {angle:g}° | " + " | ".join(cells) + " |")
    return lines + [""]


def _pct(a: float, b: float) -> str:
    return f"{(a / b - 1) * 100:+.1f} %" if np.isfinite(a) and np.isfinite(b) and b else "-"
