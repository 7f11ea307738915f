"""Adaptive POM against POM at equal error, per map, with a bootstrap interval (comparison.csv).

For one view and one error measure (p95), POM's configurations give a curve of error against SIMD-tile fetches.
Walking it in order of cost with the running minimum of the error (a costlier POM that is less accurate is never
the one to pick), POM's cost at an error e is interpolated linearly in log(cost) against log(error + 0.001 texel)
between the two configurations around e: no rounding to the next grid point. An adaptive configuration's ratio is
its SIMD-tile fetches over POM's cost at its own p95; below 1 it is the cheaper one.

A view counts when it is meaningful: its angle above 0° and at most 80°, the adaptive configuration's p95 at most
1 texel, and its error within POM's curve (not coarser than POM's fewest layers, not finer than its most). A map's
ratio is the geometric mean over its views that count; its interval is the 2.5-97.5 % range of that mean over
bootstrap resamples of the SIMD tiles (the same resample for every configuration of a view, a fixed seed).
"""

from __future__ import annotations

import numpy as np

from wgpuviewer.lab.harness.table import Column, Table

from .measure import CONFIGS, DEGENERATE

EPS = 1e-3  # texels added before the logarithm: an exact search (error 0) stays on the curve
MAX_ANGLE = 80.0
MEANINGFUL_P95 = 1.0  # texels
POM = [i for i, c in enumerate(CONFIGS) if c.technique == "pom"]
ADAPTIVE = [i for i, c in enumerate(CONFIGS) if c.technique == "pom_adaptive"]
TEXTURED = "textured maps"  # the row of every map that is not degenerate

TABLE = Table("adaptive POM at equal error", [
    Column("heightmap", str), Column("degenerate", bool), Column("config", str),
    Column("views", int, "views that count"), Column("coarser", int, "views whose error POM's fewest layers beat"),
    Column("finer", int, "views more accurate than POM's most layers"),
    Column("over_budget", int, "views whose adaptive p95 is above 1 texel"),
    Column("ratio", float, "SIMD-tile fetches over POM's at equal p95 (geometric mean)"),
    Column("low", float, "2.5 % bootstrap"), Column("high", float, "97.5 % bootstrap"), Column("verdict", str),
])


def pom_cost_at(errors: np.ndarray, costs: np.ndarray, target: float) -> tuple[float, str]:
    """POM's cost at error ``target`` on its curve, and "" or why there is none ("coarser", "finer")."""
    order = np.argsort(costs, kind="stable")
    e, c = np.minimum.accumulate(errors[order]), costs[order]
    if not np.isfinite(target) or target < e[-1]:
        return float("nan"), "finer"
    if target >= e[0]:
        return float("nan"), "coarser"
    k = int(np.argmax(e <= target))  # e[k - 1] > target >= e[k]
    x0, x1, xt = np.log(e[k - 1] + EPS), np.log(e[k] + EPS), np.log(target + EPS)
    y = np.log(c[k - 1]) + (np.log(c[k]) - np.log(c[k - 1])) * (xt - x0) / (x1 - x0)
    return float(np.exp(y)), ""


def view_ratios(p95: np.ndarray, simd: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """Per adaptive configuration: its ratio to POM at its p95 (NaN when none) and why none."""
    ratios, why = [], []
    for j in ADAPTIVE:
        cost, reason = pom_cost_at(p95[POM], simd[POM], p95[j])
        ratios.append(simd[j] / cost if np.isfinite(cost) else np.nan)
        why.append(reason)
    return np.array(ratios), why


def _resampled(view, rng, resamples: int) -> np.ndarray:
    """(resamples, adaptive configurations) ratios over bootstrap resamples of the view's SIMD tiles."""
    tiles = view.tile_max.shape[1]
    members = [np.flatnonzero(view.tile_of == t) for t in range(tiles)]
    out = np.full((resamples, len(ADAPTIVE)), np.nan)
    for b in range(resamples):
        pick = rng.integers(0, tiles, tiles)
        ray = np.concatenate([members[t] for t in pick])
        if ray.size == 0:
            continue
        with np.errstate(all="ignore"):
            p95 = np.nanpercentile(view.errors[:, ray], 95, axis=1)
        out[b] = view_ratios(p95, view.tile_max[:, pick].mean(axis=1))[0]
    return out


def _row(name: str, degenerate: bool, j: int, points: list, boots: list, counts: dict) -> dict:
    label = CONFIGS[ADAPTIVE[j]].label
    used = [(p[j], b[:, j]) for p, b in zip(points, boots) if np.isfinite(p[j])]
    row = {"heightmap": name, "degenerate": degenerate, "config": label, "views": len(used),
           "coarser": counts["coarser"][j], "finer": counts["finer"][j], "over_budget": counts["over"][j],
           "ratio": None, "low": None, "high": None, "verdict": "no view counts"}
    if not used:
        return row
    ratio = float(np.exp(np.mean([np.log(p) for p, _ in used])))
    with np.errstate(all="ignore"):
        means = np.exp(np.nanmean(np.log(np.stack([b for _, b in used], axis=1)), axis=1))
    low, high = np.nanpercentile(means, (2.5, 97.5))
    verdict = "adaptive cheaper" if high < 1 else "POM cheaper" if low > 1 else "no clear difference"
    return {**row, "ratio": ratio, "low": float(low), "high": float(high), "verdict": verdict}


def compare(views: list, resamples: int, seed: int = 0) -> list[dict]:
    """comparison.csv's rows: per map (and for all textured maps together) and adaptive configuration."""
    rng = np.random.default_rng(seed)
    per_map: dict[str, dict] = {}
    for view in views:
        with np.errstate(all="ignore"):
            p95 = np.nanpercentile(view.errors, 95, axis=1)
        ratios, why = view_ratios(p95, view.tile_max.mean(axis=1))
        entry = per_map.setdefault(view.heightmap, {"points": [], "boots": [],
                                                    "coarser": [0] * len(ADAPTIVE), "finer": [0] * len(ADAPTIVE),
                                                    "over": [0] * len(ADAPTIVE)})
        if not 0 < view.angle <= MAX_ANGLE:
            continue
        over = p95[ADAPTIVE] > MEANINGFUL_P95
        for j in range(len(ADAPTIVE)):
            entry["over"][j] += int(over[j])
            if why[j] and not over[j]:
                entry[why[j]][j] += 1
        ratios = np.where(over, np.nan, ratios)
        entry["points"].append(ratios)
        entry["boots"].append(np.where(over, np.nan, _resampled(view, rng, resamples)))
    rows = []
    for j in range(len(ADAPTIVE)):
        for name, entry in per_map.items():
            rows.append(_row(name, name in DEGENERATE, j, entry["points"], entry["boots"], entry))
        textured = [e for n, e in per_map.items() if n not in DEGENERATE]
        total = {k: [sum(e[k][j] for e in textured)] * len(ADAPTIVE) for k in ("coarser", "finer", "over")}
        rows.append(_row(TEXTURED, False, j, [p for e in textured for p in e["points"]],
                         [b for e in textured for b in e["boots"]], total))
    return rows
