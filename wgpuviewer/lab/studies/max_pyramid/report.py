"""report.md of the max-pyramid study, and the tables docs/max-pyramid.md quotes (docs.py): the paper's claim, the
measured answer per relief class (wins and the geometric-mean cost ratio against the best linear search at equal
p95 and at equal max error), the ratios per map and angle, the errors at equal cost, whether "without loss of
accuracy" holds, the per-level step statistics and the early exit. Every number is computed from the rows."""

from __future__ import annotations

import math
from pathlib import Path

from .compare import best_linear, ratio
from .figures import draw
from .tables import COMPETITORS

CLAIM = ("\"Significantly improves the performance of parallax mapping in many cases without loss of accuracy\"; "
         "the best gain on reliefs with large flat areas (brick walls), less on noisy ones; at each level at most 2 "
         "tracing steps inside the parent; if the start texel holds the global maximum, no trace is needed.")
#: A walk's hit error up to this (texels) is "no loss of accuracy": float32 rounding of an exact solve.
EXACT_TEXELS = 0.01
CRITERIA = (("p95", "p95 ≤ 0.25 texel"), ("max", "max ≤ 1 texel"))


def _geomean(xs) -> float:
    xs = [x for x in xs if x > 0 and math.isfinite(x)]
    return math.exp(sum(map(math.log, xs)) / len(xs)) if xs else float("nan")


def claim_cells(rows: list[dict], tracer: str = "maxmip") -> list[dict]:
    """Per relief class: cases, wins at each criterion (the walk cheaper than every linear search reaching the
    target), the geometric-mean ratio, the walk's largest hit error and capped share."""
    out = []
    for cls in sorted({r["relief_class"] for r in rows}):
        mine = [r for r in rows if r["relief_class"] == cls and r["tracer"] == tracer]
        cell = {"class": cls, "cases": len(mine), "maps": sorted({r["heightmap"] for r in mine}),
                "error_max": max(r["error_max"] for r in mine), "capped": max(r["capped"] for r in mine)}
        for criterion, _ in CRITERIA:
            ratios = [ratio(r, criterion)[0] for r in mine]
            cell[f"wins_{criterion}"] = sum(x < 1.0 for x in ratios)
            cell[f"geomean_{criterion}"] = _geomean(ratios)
        out.append(cell)
    return out


def _f(x, digits: int = 2) -> str:
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.{digits}f}"


def claim_table(rows: list[dict]) -> list[str]:
    """The answer per relief class and walk (markdown); accuracy: the cases whose largest hit error exceeds
    EXACT_TEXELS (or with capped rays) out of all."""
    lines = ["| walk | relief class | maps | cases | wins at p95 ≤ 0.25 | cost ratio (geomean) | wins at max ≤ 1 | "
             f"cost ratio (geomean) | largest p95 / max hit error (texels) | without loss of accuracy (max ≤ "
             f"{EXACT_TEXELS:g} texel) |", "|---|---|---|---|---|---|---|---|---|---|"]
    for tracer in sorted({r["tracer"] for r in rows}):
        for c in claim_cells(rows, tracer):
            mine = [r for r in rows if r["tracer"] == tracer and r["relief_class"] == c["class"]]
            lost = sum(r["error_max"] > EXACT_TEXELS or r["capped"] > 0 for r in mine)
            verdict = "holds" if not lost else f"fails in {lost} of {c['cases']}"
            lines.append(f"| {tracer} | {c['class']} | {', '.join(c['maps'])} | {c['cases']} | {c['wins_p95']} of "
                         f"{c['cases']} | {_f(c['geomean_p95'])} | {c['wins_max']} of {c['cases']} | "
                         f"{_f(c['geomean_max'])} | {max(r['error_p95'] for r in mine):.2g} / {c['error_max']:.2g} | "
                         f"{verdict} |")
    return lines


def ratio_table(rows: list[dict], criterion: str, tracer: str = "maxmip") -> list[str]:
    """The walk's SIMD-tile fetches over the best linear search's at the criterion, per map (rows) and angle."""
    mine = [r for r in rows if r["tracer"] == tracer]
    angles = sorted({r["angle"] for r in mine})
    lines = ["| map (class) | " + " | ".join(f"{a:g}°" for a in angles) + " |", "|---|" + "---|" * len(angles)]
    for name in dict.fromkeys(r["heightmap"] for r in mine):
        cells = []
        for a in angles:
            row = next((r for r in mine if r["heightmap"] == name and r["angle"] == a), None)
            if row is None:
                cells.append("–")
                continue
            value, bound = ratio(row, criterion)
            cells.append(f"{bound}{value:.2f} ({best_linear(row, criterion)[2]})")
        cls = next(r["relief_class"] for r in mine if r["heightmap"] == name)
        lines.append(f"| {name} ({cls}) | " + " | ".join(cells) + " |")
    return lines


def equal_cost_table(rows: list[dict], tracer: str = "maxmip") -> list[str]:
    """The best linear search's p95 and max error at the walk's SIMD-tile fetches, against the walk's own."""
    mine = [r for r in rows if r["tracer"] == tracer]
    lines = ["| map | angle | walk SIMD-tile fetches | walk p95 / max (texels) | best linear p95 at that cost | "
             "best linear max at that cost |", "|---|---|---|---|---|---|"]
    for r in mine:
        p95 = min((r[f"{c}_p95_at_simd"], r[f"{c}_flag_p95_at_simd"], c) for c in COMPETITORS)
        mx = min((r[f"{c}_max_at_simd"], r[f"{c}_flag_max_at_simd"], c) for c in COMPETITORS)
        lines.append(f"| {r['heightmap']} | {r['angle']:g}° | {r['fetches_simd']:.1f} | {r['error_p95']:.1g} / "
                     f"{r['error_max']:.1g} | {p95[1]}{p95[0]:.3g} ({p95[2]}) | {mx[1]}{mx[0]:.3g} ({mx[2]}) |")
    return lines


def level_table(level_rows: list[dict], rows: list[dict]) -> list[str]:
    """Per relief class and angle: steps per ray at each level (0 = the cells), the share of parent visits with at
    most 2 steps, the longest run inside one parent, climbs back up per ray."""
    top = max(r["level"] for r in level_rows)
    lines = ["| class | angle | " + " | ".join(f"L{m}" for m in range(top + 1)) +
             " | ≤ 2 steps in a parent | longest run | climbs per ray |", "|---|---|" + "---|" * (top + 4)]
    for cls in sorted({r["relief_class"] for r in level_rows}):
        for a in sorted({r["angle"] for r in level_rows}):
            mine = [r for r in level_rows if r["relief_class"] == cls and r["angle"] == a]
            walks = [r for r in rows if r["relief_class"] == cls and r["angle"] == a and r["tracer"] == "maxmip"]
            if not mine:
                continue
            maps = len({r["heightmap"] for r in mine})
            steps = [sum(r["steps_per_ray"] for r in mine if r["level"] == m) / maps for m in range(top + 1)]
            visits = sum(r["parent_visits"] for r in mine)
            two = sum(r["within_two"] * r["parent_visits"] for r in mine if r["parent_visits"]) / visits
            lines.append(f"| {cls} | {a:g}° | " + " | ".join(f"{s:.2f}" for s in steps) +
                         f" | {two:.1%} | {max(r['most_in_parent'] for r in mine)} | "
                         f"{sum(w['climbs'] for w in walks) / len(walks):.2f} |")
    return lines


def early_exit_table(rows: list[dict]) -> list[str]:
    mine = [r for r in rows if r["tracer"] == "maxmip"]
    lines = ["| map | angle | rays it fires on | largest hit error where it fires (texels) | SIMD-tile fetches "
             "without / with it |", "|---|---|---|---|---|"]
    for r in mine:
        lines.append(f"| {r['heightmap']} | {r['angle']:g}° | {r['early_exit_share']:.1%} | "
                     f"{_f(r['early_exit_error_max'], 3)} | {r['fetches_simd']:.2f} / {r['early_exit_simd']:.2f} |")
    return lines


def twin_line(rows: list[dict]) -> str:
    walks = [r for r in rows if r["tracer"] == "maxmip"]
    worst = max(walks, key=lambda r: r["twin_hit_diff"])
    return (f"The twin and the GPU probe of `maxmip` agree on the fetch count of at least "
            f"{min(r['twin_same_fetches'] for r in walks):.2%} and on the hit (within 0.001 texel) of at least "
            f"{min(r['twin_hits_agree'] for r in walks):.2%} of the rays of every view. The largest disagreement, "
            f"{worst['twin_hit_diff']:.3g} texels ({worst['heightmap']}, {worst['angle']:g}°), is the GPU's: the "
            f"float64 twin's largest error against the exact hit in any view is "
            f"{max(r['twin_error_max'] for r in walks):.2g} texels.")


def report(rows: list[dict], level_rows: list[dict], header, out: Path, pictures: bool = True) -> str:
    """report.md's text; with ``pictures`` the pictures are drawn into ``out`` and linked."""
    pictures = draw(rows, out) if pictures else []
    lines = [*header.lines(), "", "## The paper's claim", "", CLAIM, "", "## Method", "",
             "Every pixel of the benchmark's full-screen view (bench.view: the plane turned 30° about its normal, "
             "relief depth 0.05 UV) is one ray, traced by the GPU probe (the renderer's own `trace`); cost is the "
             "SIMD-tile fetches (the mean over 8x4 pixel tiles of the tile's largest count), error the hit's "
             "distance in texels to the float64 exact first hit of the bilinear surface (`reference.exact_hit`). "
             "steep, pom and relief are swept over their layer counts; their cost at an error target is "
             "interpolated in log-log on that curve (a leading `<` or `>=` marks a bound: no setting reached the "
             "target, or the cheapest already did). The ratio is the walk's cost over the cheapest linear search's: "
             "below 1 the walk wins.", "", "## The answer per relief class", "", *claim_table(rows), "",
             "## Cost ratio per map and angle (maxmip over the cheapest linear search)", "",
             "At p95 ≤ 0.25 texel:", "", *ratio_table(rows, "p95"), "", "At max ≤ 1 texel:", "",
             *ratio_table(rows, "max"), "", "## At equal SIMD-tile fetches", "", *equal_cost_table(rows), "",
             "## Steps per level (the instrumented twin of maxmip)", "", twin_line(rows), "",
             *level_table(level_rows, rows), "", "## The early exit", "", *early_exit_summary(rows), "",
             *early_exit_table(rows), ""]
    if pictures:
        lines += ["## Pictures", ""] + [f"![{p}]({p})" for p in pictures] + [""]
    return "\n".join(lines)


def early_exit_summary(rows: list[dict]) -> list[str]:
    """Per map over its angles: the share of rays the early exit fires on (least to most), its largest hit error,
    and the walk's SIMD-tile fetches without and with it (geometric means)."""
    mine = [r for r in rows if r["tracer"] == "maxmip"]
    lines = ["| map | rays it fires on (over the angles) | largest hit error where it fires (texels) | SIMD-tile "
             "fetches without / with it (geomean) |", "|---|---|---|---|"]
    for name in dict.fromkeys(r["heightmap"] for r in mine):
        rs = [r for r in mine if r["heightmap"] == name]
        shares = [r["early_exit_share"] for r in rs]
        errors = [r["early_exit_error_max"] for r in rs if r["early_exit_error_max"] is not None]
        lines.append(f"| {name} | {min(shares):.1%} to {max(shares):.1%} | {_f(max(errors) if errors else None, 3)} | "
                     f"{_geomean(r['fetches_simd'] for r in rs):.2f} / {_geomean(r['early_exit_simd'] for r in rs):.2f} |")
    return lines
