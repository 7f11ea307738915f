"""The adaptive-POM study's report.md and curves.png, and the tables docs/benchmarks.md's block shares
(``summary``, ``per_map``, ``curve_points``)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.harness.plots import MISSING, pyplot, save_png

from .compare import EPS, MAX_ANGLE, MEANINGFUL_P95, TEXTURED
from .measure import DEGENERATE, NMAX, NMIN, POM_LAYERS

PICTURE = "curves.png"
MAIN = "adaptive 4-32"  # the thesis' setting (the registry's defaults)


def _n(x, digits: int = 2) -> str:
    return "–" if x is None or not math.isfinite(x) else f"{x:.{digits}f}"


def _times(x) -> str:
    return "–" if x is None or not math.isfinite(x) else f"{x:.2f}×"


def _span(r: dict) -> str:
    return "–" if r["low"] is None else f"{_n(r['low'])}-{_n(r['high'])}"


def summary(comparison: list[dict]) -> list[str]:
    """Every adaptive configuration on the textured maps together: ratio, interval, verdict, views."""
    lines = ["| configuration | fetches vs POM at equal p95 | 95 % interval | verdict | views (coarser / finer / "
             "p95 > 1 texel) |", "|---|---|---|---|---|"]
    for r in comparison:
        if r["heightmap"] == TEXTURED:
            lines.append(f"| `{r['config']}` | {_times(r['ratio'])} | {_span(r)} | {r['verdict']} | "
                         f"{r['views']} ({r['coarser']} / {r['finer']} / {r['over_budget']}) |")
    return lines


def per_map(comparison: list[dict], config: str = MAIN) -> list[str]:
    """One configuration per map: the textured maps, then the degenerate ones apart."""
    lines = [f"| map (`{config}`) | fetches vs POM at equal p95 | 95 % interval | sign | views |", "|---|---|---|---|---|"]
    rows = [r for r in comparison if r["config"] == config and r["heightmap"] != TEXTURED]
    for r in sorted(rows, key=lambda r: (r["degenerate"], r["heightmap"])):
        name = f"{r['heightmap']} (degenerate)" if r["degenerate"] else r["heightmap"]
        lines.append(f"| {name} | {_times(r['ratio'])} | {_span(r)} | {r['verdict']} | "
                     f"{r['views']} |")
    return lines


def curve_points(rows: list[dict], metric: str) -> dict[str, tuple[float, float]]:
    """Per configuration (SIMD-tile fetches, error) as geometric means over the textured maps' views above 0° and
    at most 80° (errors + EPS, so that an exact view counts)."""
    found: dict[str, list[tuple[float, float]]] = {}
    for r in rows:
        if r["heightmap"] in DEGENERATE or not 0 < r["angle"] <= MAX_ANGLE or not math.isfinite(r[metric]):
            continue
        found.setdefault(r["config"], []).append((r["fetches_simd"], r[metric] + EPS))
    return {c: tuple(float(np.exp(np.mean(np.log(v)))) for v in zip(*points)) for c, points in found.items()}


def brick_lines(rows: list[dict], heightmap: str = "brick") -> list[str]:
    """The thesis' claim of detail comparable to POM 32, on one map: p95 of adaptive 4-32 and of POM 32 by angle."""
    pick = {(r["config"], r["angle"]): r for r in rows if r["heightmap"] == heightmap}
    angles = sorted({a for _, a in pick if 0 < a <= MAX_ANGLE})
    if not angles:
        return []
    lines = [f"| {heightmap}: p95 (texels) at | " + " | ".join(f"{a:g}°" for a in angles) + " |",
             "|---|" + "---|" * len(angles)]
    for config in (MAIN, "pom 32"):
        lines.append(f"| `{config}` | " + " | ".join(_n(pick[(config, a)]["p95"]) for a in angles) + " |")
    return lines


def plot(out: Path, rows: list[dict]) -> str | None:
    """curves.png: p95, p99 and max error against SIMD-tile fetches, POM's curve and every adaptive setting."""
    with pyplot() as plt:
        if plt is None:
            return None
        fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
        colours = dict(zip(NMIN, ("tab:orange", "tab:green", "tab:red")))
        sizes = dict(zip(NMAX, (25, 55, 100)))
        for ax, metric in zip(axes, ("p95", "p99", "max")):
            points = curve_points(rows, metric)
            pom = [points[f"pom {n}"] for n in POM_LAYERS if f"pom {n}" in points]
            ax.plot(*zip(*pom), "-o", color="tab:blue", ms=3, label="pom (4 to 256 layers)")
            for n, (x, y) in zip(POM_LAYERS, pom):
                ax.annotate(str(n), (x, y), fontsize=7, xytext=(3, 3), textcoords="offset points")
            for only in (False, True):
                for a in NMIN:
                    for b in NMAX:
                        label = f"adaptive{' angle-only' if only else ''} {a}-{b}"
                        if label in points:
                            ax.scatter(*points[label], s=sizes[b], marker="s" if only else "o",
                                       facecolors="none" if only else colours[a], edgecolors=colours[a])
            ax.set(xscale="log", yscale="log", xlabel="SIMD-tile depth fetches", ylabel=f"{metric} UV error (texels)",
                   title=f"{metric}, textured maps, 30-80° (geometric means)")
            ax.grid(True, which="both")
        handles = [plt.Line2D([], [], color="tab:blue", marker="o", ms=3, label="pom (layers annotated)")]
        handles += [plt.Line2D([], [], ls="", marker="o", color=colours[a], label=f"adaptive Nmin {a}") for a in NMIN]
        handles += [plt.Line2D([], [], ls="", marker="s", mfc="none", color="grey", label="angle-only (hollow)"),
                    plt.Line2D([], [], ls="", marker="o", color="grey", label="marker size: Nmax 16/32/64")]
        axes[0].legend(handles=handles, fontsize=7, loc="lower left")
        return save_png(fig, out / PICTURE, dpi=80)


def write_report(out: Path, rows: list[dict], comparison: list[dict], header, suite) -> None:
    picture = plot(out, rows)
    lines = [*header.lines(), f"- maps: {', '.join(suite.heightmaps)} (degenerate, reported apart: "
             f"{', '.join(d for d in DEGENERATE if d in suite.heightmaps) or 'none'}); angles: "
             f"{', '.join(f'{a:g}°' for a in suite.angles)}; {suite.grid[0]}x{suite.grid[1]} rays per view; "
             f"{suite.resamples} bootstrap resamples", "",
             "Method: docs/benchmarks.md (adaptive POM against POM). A view counts when its angle is above 0° and at "
             f"most {MAX_ANGLE:g}° and the adaptive p95 is at most {MEANINGFUL_P95:g} texel.", "",
             "## All textured maps together", "", *summary(comparison), "", f"## Per map: `{MAIN}`", "",
             *per_map(comparison), "", "## Detail against POM 32", "", *brick_lines(rows), ""]
    lines += [f"![error against SIMD-tile fetches]({picture})" if picture else MISSING, ""]
    write_bytes(out / "report.md", "\n".join(lines).encode("utf-8"))
