"""The contact study's tables, for its report.md and docs/techniques.md's block (``docs``): the p95 error and the
SIMD-tile fetches of contact over relief's, pair by pair (same linear search, same fetch bound), by height map and
angle and by the extra fetches; and at equal measured cost, how often contact beats every relief setting that costs
no more SIMD-tile fetches on the same map and angle."""

from __future__ import annotations

from collections import defaultdict

import numpy as np

#: Added to both p95 errors before a ratio (float32's floor of a hit's position, 1e-3 texel): two exact finishes tie.
FLOOR = 1e-3
#: A ratio within this of 1 is a tie.
TIE = 0.05


def _ratio(contact: float, relief: float) -> float:
    if np.isinf(contact) and np.isinf(relief):
        return 1.0
    return (min(contact, 1e9) + FLOOR) / (min(relief, 1e9) + FLOOR)


def pairs(rows: list[dict]) -> dict[tuple, dict[str, dict]]:
    """(heightmap, angle, linear_steps, extra) -> technique -> row."""
    out: dict[tuple, dict[str, dict]] = defaultdict(dict)
    for r in rows:
        out[r["heightmap"], r["angle"], r["linear_steps"], r["extra"]][r["technique"]] = r
    return {k: v for k, v in out.items() if len(v) == 2}


def _geomean(values) -> float:
    return float(np.exp(np.mean(np.log(values))))


def ratios_by(rows: list[dict], key, column: str) -> dict:
    """Geometric mean of contact's ``column`` over relief's per ``key(pair key)``."""
    groups = defaultdict(list)
    for k, pair in pairs(rows).items():
        c, r = pair["contact"][column], pair["relief"][column]
        groups[key(k)].append(_ratio(c, r) if column.startswith("err") else c / max(r, 1e-9))
    return {k: _geomean(v) for k, v in groups.items()}


def _cell(x: float) -> str:
    mark = "**" if x < 1 - TIE else ""
    return f"{mark}{x:.2f}{mark}"


def map_angle_table(rows: list[dict], column: str) -> list[str]:
    """Markdown: one row per height map, one column per angle, the geometric mean of contact / relief."""
    by = ratios_by(rows, lambda k: (k[0], k[1]), column)
    maps = list(dict.fromkeys(r["heightmap"] for r in rows))
    angles = sorted({r["angle"] for r in rows})
    lines = ["| height map | " + " | ".join(f"{a:g}°" for a in angles) + " |", "|---|" + "---|" * len(angles)]
    lines += [f"| {m} | " + " | ".join(_cell(by[m, a]) for a in angles) + " |" for m in maps]
    return lines


def extra_line(rows: list[dict]) -> str:
    """contact / relief p95 by the extra fetches, over every map, angle and linear search."""
    by = ratios_by(rows, lambda k: k[3], "err_p95")
    return "; ".join(f"{e} extra: {by[e]:.2f}" for e in sorted(by))


def relief_frontier_at(relief: list[dict], cost: float) -> float | None:
    """Relief's p95 at ``cost`` SIMD-tile fetches on one map and angle: its settings' lower envelope (the least p95 at
    no more cost), interpolated linearly in log(p95 + FLOOR) between the envelope's points; None outside their cost
    range."""
    points = sorted((r["fetches_simd"], min(r["err_p95"], 1e9) + FLOOR) for r in relief)
    envelope, best = [], np.inf
    for x, e in points:
        best = min(best, e)
        envelope.append((x, best))
    xs = np.array([x for x, _ in envelope])
    if not xs[0] <= cost <= xs[-1]:
        return None
    return float(np.exp(np.interp(cost, xs, np.log([e for _, e in envelope])))) - FLOOR


def cost_beaten(rows: list[dict]) -> tuple[int, int, list[tuple[str, float]]]:
    """At equal measured cost: (contact settings whose p95 is below relief's interpolated envelope at their SIMD-tile
    fetches by more than the tie, contact settings within the envelope's cost range, the (map, angle) of each win)."""
    by = defaultdict(lambda: defaultdict(list))
    for r in rows:
        by[r["heightmap"], r["angle"]][r["technique"]].append(r)
    wins, total, where = 0, 0, []
    for key, group in by.items():
        for c in group["contact"]:
            relief = relief_frontier_at(group["relief"], c["fetches_simd"])
            if relief is not None:
                total += 1
                if _ratio(c["err_p95"], relief) < 1 - TIE:
                    wins += 1
                    where.append(key)
    return wins, total, where


def cell_counts(rows: list[dict]) -> tuple[int, int, int]:
    """(map x angle cells where contact's p95 is lower by more than the tie, ties, cells where relief's is)."""
    by = ratios_by(rows, lambda k: (k[0], k[1]), "err_p95").values()
    return (sum(x < 1 - TIE for x in by), sum(abs(x - 1) <= TIE for x in by), sum(x > 1 + TIE for x in by))


def report(rows: list[dict]) -> list[str]:
    """The tables (markdown lines): the summary, p95 ratio by map and angle, SIMD-fetch ratio, by extra fetches."""
    contact, tie, relief = cell_counts(rows)
    wins, total, where = cost_beaten(rows)
    places = ", ".join(f"{m} {a:g}°" for m, a in dict.fromkeys(where)) or "none"
    return [
        f"Per height map and angle, contact's p95 error is lower in {contact}, within {TIE:.0%} in {tie} and higher in "
        f"{relief} of {contact + tie + relief} cells (geometric mean over the pairs of contact / relief, same linear "
        f"search and fetch bound; **bold**: contact lower). At equal measured cost (relief's settings' lower envelope "
        f"of p95 against SIMD-tile fetches on the same map and angle, interpolated), {wins} of the {total} contact "
        f"settings within its range are lower by more than {TIE:.0%} (where: {places}).", "",
        "contact p95 / relief p95:", "", *map_angle_table(rows, "err_p95"), "",
        "contact / relief SIMD-tile fetches (contact's second search stops at the first sub-step below the surface):",
        "", *map_angle_table(rows, "fetches_simd"), "",
        f"contact p95 / relief p95 by the extra fetches beyond the linear search: {extra_line(rows)}.",
    ]
