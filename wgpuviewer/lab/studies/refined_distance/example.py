"""The paper's worked example (Romanyuk et al. 2017, figures 5-8) rebuilt on a bilinear height field: a point C
3 texels from the nearest surface, whose refined value (the least free path over the directions that reach C
unblocked from the top) is 4, so a ray through C needs one step instead of two.

The relief: a slot PIT texels wide (depth 1, height 0) in a flat top, DEPTH texels deep (metric), constant along v;
its bilinear walls slope over one texel. C sits on the slot's middle line at depth C_DEPTH. DEPTH and C_DEPTH are
the solution of two conditions (solved with the geometry below, not tuned by measurement): C is exactly 3 texels
from both walls (the Euclidean value), and the steepest rays that still enter the slot through its opening and pass
through C (the rim-grazing rays V1 and V2, polar angle atan(half opening / C_DEPTH)) meet the opposite walls exactly
4 texels on (the refined value; the floor, 4.3 below, is farther). Every direction that reaches C is at most that
steep, and a less steep one meets a wall or the floor farther on, so the refined value is 4.

``solve`` measures it with ``exact.point_paths`` (dense directions over the 85° cone), ``steps`` runs Donnelly's
loop on the point values, ``plot`` draws the cross-section (``worked_example.png``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer.lab.harness.table import Column, Table

from . import exact

WIDTH, ROWS = 32, 4  # texels: the map (the slot runs along v, so few rows do)
PIT = 6  # texels of the slot (depth 1)
FIRST = 13  # first texel of the slot
DEPTH = 8.230131532862327  # metric depth of the slot, texels
C_DEPTH = 3.9334764185386617  # depth of C, texels
EUCLIDEAN, REFINED = 3.0, 4.0  # the paper's values at C
MAX_ANGLE = 85.0  # the cone of directions (the product's refined map's)
#: The dense directions: polar angles every POLAR_STEP degrees up to MAX_ANGLE, azimuths every AZIMUTH_STEP.
POLAR_STEP, AZIMUTH_STEP = 0.1, 2.0
#: The run's picture of it.
PLOT = "worked_example.png"


def height() -> np.ndarray:
    h = np.ones((ROWS, WIDTH), np.float32)
    h[:, FIRST:FIRST + PIT] = 0.0
    return h


def height_scale() -> float:
    return DEPTH / WIDTH


def point_c() -> tuple[float, float, float]:
    """C in texel coordinates (x, y; texel i spans [i, i + 1)) and layer depth t."""
    return FIRST + PIT / 2.0, ROWS / 2.0, C_DEPTH / DEPTH


def rim_angle() -> float:
    """Polar angle (degrees) of V1 and V2: through C and a rim of the opening (texel centres FIRST - 0.5 and
    FIRST + PIT + 0.5, at depth 0)."""
    return math.degrees(math.atan((PIT + 1) / 2.0 / C_DEPTH))


def cone_directions() -> np.ndarray:
    """Tangent-space V (towards the eye) on the dense grid of the cone; travel w = (-V.x, -V.y, V.z)."""
    polar = np.radians(np.arange(0.0, MAX_ANGLE + 1e-9, POLAR_STEP))
    az = np.radians(np.arange(0.0, 360.0, AZIMUTH_STEP))
    p, a = (g.ravel() for g in np.meshgrid(polar, az))
    return np.stack([np.sin(p) * np.cos(a), np.sin(p) * np.sin(a), np.cos(p)], axis=1)


def travel(polar_deg: float, leftwards: bool) -> np.ndarray:
    """V of a ray in the map's cross-section travelling down and left (or right) at ``polar_deg``."""
    s = math.sin(math.radians(polar_deg))
    return np.array([[s if leftwards else -s, 0.0, math.cos(math.radians(polar_deg))]])


@dataclass
class Example:
    euclidean: float  # texels: least free path from C over every direction of the cone
    refined: float  # texels: the same over the directions that reach C unblocked
    steepest_visible: float  # degrees: the steepest polar angle among them across the slot
    steps_euclidean: list[float]  # Donnelly's steps along V1 with the Euclidean values
    steps_refined: list[float]  # and with the refined ones
    hit_v1: float  # texels from C to V1's hit A


def value(point, visible_only: bool, directions=None) -> float:
    d = 1.0 - height().astype(np.float64)
    v = cone_directions() if directions is None else directions
    return float(exact.point_paths(d, point, v, height_scale(), visible_only).min())


def steps(point, view_dir: np.ndarray, visible_only: bool, hit: float, count: int = 3) -> list[float]:
    """Donnelly's loop from ``point`` along one ray: each step the point's value (the least free path over the cone's
    directions, those reaching it unblocked with ``visible_only``); stops at the hit (within 1e-3 texel)."""
    x, y, t = point
    v = view_dir[0]
    per_t = WIDTH * height_scale() / v[2]  # texels along the ray per unit layer depth
    dxy = -v[:2] / v[2] * height_scale() * WIDTH
    out, travelled = [], 0.0
    for _ in range(count):
        if hit - travelled <= 1e-3:
            break
        s = value((x, y, t), visible_only)
        out.append(s)
        travelled += s
        t += s / per_t
        x, y = x + dxy[0] * s / per_t, y + dxy[1] * s / per_t
    return out


def solve() -> Example:
    c = point_c()
    d = 1.0 - height().astype(np.float64)
    v = cone_directions()
    visible = np.isfinite(exact.point_paths(d, c, v, height_scale(), True))
    polar = np.degrees(np.arccos(v[:, 2]))
    across = np.abs(v[:, 1]) < 1e-9  # in the cross-section: along the slot nothing blocks a ray
    v1 = travel(rim_angle() - 1e-6, leftwards=True)
    hit = float(exact.point_paths(d, c, v1, height_scale(), False)[0])
    return Example(value(c, False), value(c, True), float(polar[visible & across].max()),
                   steps(c, v1, False, hit), steps(c, v1, True, hit), hit)


#: Sector counts whose conservative cut the example reports: the paper's single cone, and 8 sectors (the product's 4
#: each hold a direction along the slot, which nothing blocks, so they cut nothing here either).
CUT_SECTORS = (1, 8)


def conservative_cut(sectors: int) -> float:
    """The steepest polar angle (degrees) the product's visibility cut lets reach C's voxel, for the sector holding
    V1's azimuth (travel towards -u) out of ``sectors``."""
    from maptools.kinds.distance_refined.visibility import horizon
    from maptools.volume.slot import DISTANCE_SLICES

    x, y, t = point_c()
    at = (np.array([int(t * DISTANCE_SLICES)]), np.array([int(y)]), np.array([int(x)]))
    g = horizon(1.0 - height().astype(np.float64), DISTANCE_SLICES, height_scale(), sectors, MAX_ANGLE, 16.0, at=at)
    cot = float(g[-1, 0])  # the last sector ends at azimuth pi: travel towards -u
    return MAX_ANGLE if cot <= 0 else math.degrees(math.atan(1.0 / cot))


#: example.csv: the worked example's numbers, one row.
TABLE = Table("refined-distance worked example", (
    Column("euclidean", float, "texels: least free path from C over the cone"),
    Column("refined", float, "texels: the same over the directions that reach C unblocked"),
    Column("hit_v1", float, "texels from C to V1's hit A"), Column("horizon", float, "degrees: V1's polar angle"),
    Column("steps_euclidean", str, "Donnelly's steps along V1, texels"), Column("steps_refined", str),
    Column("cut_single", float, "degrees: the conservative cut at C's voxel, single cone"),
    Column("cut_sectors", float, f"degrees: the same with {CUT_SECTORS[-1]} sectors"),
))


def row(ex: Example, cuts: dict[int, float]) -> dict:
    return {"euclidean": ex.euclidean, "refined": ex.refined, "hit_v1": ex.hit_v1, "horizon": rim_angle(),
            "steps_euclidean": " ".join(f"{s:.4f}" for s in ex.steps_euclidean),
            "steps_refined": " ".join(f"{s:.4f}" for s in ex.steps_refined),
            "cut_single": cuts[CUT_SECTORS[0]], "cut_sectors": cuts[CUT_SECTORS[-1]]}


def section(ex: Example, cuts: dict[int, float], plotted: str) -> list[str]:
    """The report's lines on the worked example."""
    return ["## The paper's worked example", "",
            f"A slot {PIT} texels wide and {DEPTH:.2f} deep (`studies/refined_distance/example.py`); C on its middle "
            f"line {C_DEPTH:.2f} below the top. Measured with the float64 surface over {len(cone_directions())} "
            f"directions of the {MAX_ANGLE:g}° cone: Euclidean value {ex.euclidean:.3f} texels, refined value (only the "
            f"directions that reach C unblocked; across the slot the steepest of them is {ex.steepest_visible:.1f}°) "
            f"{ex.refined:.3f}; "
            f"V1's hit A is {ex.hit_v1:.3f} texels from C. Donnelly's loop along V1: Euclidean steps "
            f"{', '.join(f'{s:.3f}' for s in ex.steps_euclidean)} (A not reached after the first); refined "
            f"{', '.join(f'{s:.3f}' for s in ex.steps_refined)}. The product's conservative cut lets rays up to "
            + ", ".join(f"{c:.1f}° ({n} sector{'s' if n > 1 else ''})" for n, c in cuts.items())
            + f" reach C's voxel across the slot (the exact horizon: {rim_angle():.1f}°): one cut per sector must "
            f"hold for every azimuth in it, and along the slot nothing blocks. {plotted}", ""]


def plot(ex: Example, cuts: dict[int, float], path: Path) -> bool:
    """The cross-section: the relief, C, the Euclidean circle, V1 and V2 to A and B, the exact and conservative
    cuts. False without matplotlib."""
    from wgpuviewer.lab.harness.plots import pyplot, save_png

    with pyplot() as plt:
        if plt is None:
            return False
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        xs = np.array([0, FIRST - 0.5, FIRST + 0.5, FIRST + PIT - 0.5, FIRST + PIT + 0.5, WIDTH])
        zs = np.array([0, 0, DEPTH, DEPTH, 0, 0])
        ax.fill(np.r_[xs, WIDTH, 0], np.r_[zs, DEPTH + 1.5, DEPTH + 1.5], color="0.8", label="relief (bilinear)")
        cx, _, t = point_c()
        cz = t * DEPTH
        ax.add_patch(plt.Circle((cx, cz), ex.euclidean, fill=False, ls=":", color="C3",
                                label=f"Euclidean value {ex.euclidean:.2f}"))
        for sign, name in ((-1, "V1 → A"), (1, "V2 → B")):
            a = math.radians(rim_angle())
            back, on = cz / math.cos(a), ex.hit_v1
            ax.plot([cx - sign * back * math.sin(a), cx + sign * on * math.sin(a)],
                    [cz - back * math.cos(a), cz + on * math.cos(a)], color="C0" if sign < 0 else "C2",
                    label=f"{name}: {on:.2f} (refined value {ex.refined:.2f})")
        for n, cut in cuts.items():
            c = math.radians(cut)
            ax.plot([cx, cx + cz * math.tan(c)], [cz, 0], "--", lw=0.9,
                    label=f"conservative cut, {n} sector{'s' if n > 1 else ''}: {cut:.1f}°")
        ax.plot([cx], [cz], "ko")
        ax.annotate("C", (cx, cz), textcoords="offset points", xytext=(6, -12))
        ax.set_xlim(FIRST - 4, FIRST + PIT + 4)
        ax.set_ylim(DEPTH + 1.0, -1.0)
        ax.set_aspect("equal")
        ax.set_xlabel("u (texels)", fontsize=8)
        ax.set_ylabel("depth (texels)", fontsize=8)
        ax.legend(fontsize=7, loc="lower left", bbox_to_anchor=(1.0, 0.0))
        ax.set_title("The paper's point C: Euclidean 3, refined 4", fontsize=9)
        save_png(fig, path)
    return True
