"""``wgpuviewer curved``: the tangent-plane trace against the curved exact hit (geometry.py) on the benchmark's
height maps, per surface, height scale, S/R and view angle: error percentiles in texels, the rays the curved surface
loses at its silhouette, the rule and the limits; and relief techniques on the GPU (the probe) on the same rays
against the same curved truth, beside their own error against the flat one; results.csv, report.md and two plots.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer.core.io import write_bytes
from wgpuviewer.lab.harness import suite as harness_suite
from wgpuviewer.lab.harness.header import Clock, Header
from wgpuviewer.lab.harness.plots import MISSING, pyplot, save_png
from wgpuviewer.lab.harness.table import Column, Table
from wgpuviewer.relief.accuracy import random_rays
from wgpuviewer.relief.reference import exact_hit, uv_error_texels

from .geometry import Surface, compare

#: The tracer of the rows that measure the tangent-plane exact hit itself (the others name a technique).
EXACT = "tangent plane (exact)"
#: The report's adapter line without techniques: the study is then float64 numpy, no GPU.
CPU_ONLY = "none: float64 on the CPU (numpy)"
#: The error budgets the limit table answers for, in texels (p95 over the rays).
BUDGETS = (0.25, 0.5, 1.0)
#: S/R up to which the error is in its linear regime (where the rule is fitted).
LINEAR_UP_TO = 0.02


@dataclass(frozen=True)
class Suite(harness_suite.Suite):
    heightmaps: tuple[str, ...]
    size: int  # texels per side of the builtins and the largest side of the real maps
    height_scales: tuple[float, ...]
    surfaces: tuple[str, ...]
    ratios: tuple[float, ...]  # S/R
    angles: tuple[float, ...]
    rays: int
    techniques: tuple[str, ...]  # traced on the GPU on the same rays (default parameters)


SUITES = harness_suite.suites(
    Suite("smoke", ("bricks",), 32, (0.05,), ("sphere",), (0.01, 0.1), (30.0, 80.0), 64, ("pom",)),
    Suite("full", ("brick", "gravel", "bricks", "bumps", "wall", "spike"), 128, (0.05, 0.02), ("sphere", "cylinder"),
          (0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2), (0.0, 30.0, 45.0, 60.0, 70.0, 75.0, 80.0, 85.0), 1024,
          ("pom", "maxmip")),
)

#: results.csv: one row per height map x surface x height scale x S/R x angle x tracer (EXACT, or a technique).
TABLE = Table("curved-surface results", (
    Column("heightmap", str), Column("size", str, "texels, WxH"), Column("tracer", str), Column("surface", str),
    Column("height_scale", float, "UV units (S)"), Column("depth_texels", float, "S times the larger side"),
    Column("s_over_r", float, "S/R"), Column("radius", float, "UV units (R)"), Column("angle", float, "degrees"),
    Column("rays", int), Column("both_hit", float, "of the rays"),
    Column("curved_miss", float, "of the rays: the tangent plane hits, the curved surface is left (silhouette)"),
    Column("capped", float, "of the rays: too long to trace (EXACT: the curved hit; a technique: its cap)"),
    Column("err_p50", float, "texels"), Column("err_p95", float, "texels"), Column("err_max", float, "texels"),
    Column("err_mean", float, "texels"),
    Column("own_p95", float, "texels: a technique's p95 against the flat exact hit (its own error); empty for EXACT"),
))

TITLE = "Relief on curved surfaces: the tangent-plane trace against the curved exact hit"


def run(suite_name: str, out: Path, heightmaps=None, angles=None, ratios=None, surfaces=None, rays=None,
        techniques=None, backend: str | None = None, progress: bool = True,
        command: str = "wgpuviewer curved") -> list[dict]:
    """Measure ``SUITES[suite_name]`` (its fields replaced by the given ones; ``techniques`` () for none: then no GPU
    starts); write ``out``/results.csv, report.md and the plots; return the rows."""
    from tqdm import tqdm

    from wgpuviewer.lab.bench.run import REAL_MAPS, skimage_available
    from wgpuviewer.lab.bench.view import load_heightmap

    suite = harness_suite.pick(SUITES, suite_name)
    clock = Clock()
    maps = tuple(heightmaps or suite.heightmaps)
    if heightmaps is None and not skimage_available():
        maps = tuple(m for m in maps if m not in REAL_MAPS)
    angles = tuple(angles or suite.angles)
    ratios = tuple(ratios or suite.ratios)
    surfaces = tuple(surfaces or suite.surfaces)
    n_rays = rays or suite.rays
    techniques = tuple(suite.techniques if techniques is None else techniques)
    adapter = CPU_ONLY
    if techniques:
        from wgpuviewer.core.gpu import get_gpu

        gpu = get_gpu(backend, quiet=True)
        adapter = f"{gpu.summary} (the techniques); the exact hits float64 on the CPU"
    rows: list[dict] = []
    out = Path(out)  # checked and made by the command first (harness.study.run_study)
    total = len(maps) * len(suite.height_scales) * len(angles)
    with tempfile.TemporaryDirectory(prefix="wgpuviewer-curved-") as workdir, \
            tqdm(total=total, desc="curved", unit="view", disable=not progress) as bar:
        for name in maps:
            heightmap = load_heightmap(name, suite.size, Path(workdir), real_size=suite.size)
            depth = 1.0 - heightmap.height.astype(np.float64)
            for scale in suite.height_scales:
                for angle in angles:
                    uv, view = random_rays(n_rays, angle, seed=int(angle * 100))
                    flat = exact_hit(depth, uv, view, scale)  # the tangent-plane hit: the same for every surface
                    traced = {name: _probe(name, heightmap, uv, view, scale, flat, backend) for name in techniques}
                    for kind in surfaces:
                        for ratio in ratios:
                            result = compare(depth, Surface(kind, scale / ratio), uv, view, scale, flat)
                            rows.append(_row(heightmap, EXACT, kind, scale, ratio, angle, result.error,
                                             result.curved.miss & result.flat_valid, result.curved.capped))
                            for name, (hit_uv, capped, own) in traced.items():
                                error = np.full(len(uv), np.nan)
                                both = result.curved.hit & ~capped
                                error[both] = uv_error_texels(hit_uv[both], result.curved.uv[both], heightmap.size)
                                rows.append(_row(heightmap, name, kind, scale, ratio, angle, error,
                                                 result.curved.miss, capped, own))
                    bar.update()
            _write(out, rows, clock.header(TITLE, command, adapter, suite.name))
    return rows


def _probe(name: str, heightmap, uv, view, scale: float, flat, backend):
    """A technique's hits on the rays (the GPU probe), its capped rays and its own p95 against the flat exact hit."""
    from wgpuviewer.relief.probe import probe

    got = probe(name, heightmap.height, uv, view, scale, backend=backend)
    ok = flat.valid & ~got.capped
    own = uv_error_texels(got.uv[ok], flat.uv[ok], heightmap.size)
    return got.uv, got.capped, float(np.percentile(own, 95)) if own.size else math.nan


def _row(heightmap, tracer: str, kind: str, scale: float, ratio: float, angle: float, error, lost, capped,
         own: float | None = None) -> dict:
    w, h = heightmap.size
    finite = error[np.isfinite(error)]
    p50, p95, p_max = np.percentile(finite, [50, 95, 100]) if finite.size else (math.nan,) * 3
    return {"heightmap": heightmap.name, "size": f"{w}x{h}", "tracer": tracer, "surface": kind, "height_scale": scale,
            "depth_texels": scale * max(w, h), "s_over_r": ratio, "radius": scale / ratio, "angle": angle,
            "rays": len(error), "both_hit": float(np.isfinite(error).mean()), "curved_miss": float(lost.mean()),
            "capped": float(capped.mean()), "err_p50": p50, "err_p95": p95, "err_max": p_max,
            "err_mean": float(finite.mean()) if finite.size else math.nan, "own_p95": own}


# --- the rule ----------------------------------------------------------------------------------------------------


def first_order(angle: float, depth_texels: float, ratio: float) -> float:
    """The rule: texels between the hits of a ray that hits at the relief's full depth, to first order in S/R,
    depth_texels * S/R * (tan^3(theta) / 2 + tan(theta)). Two terms: after x of travel the shell lies x^2 / 2R below
    the tangent plane, so the ray reaches a depth later (tan^3 / 2); and a point below the shell has the uv of its
    radial projection, R / (R - depth) farther out (tan). A hit at depth d scales both by d^2 (a constant depth map
    gives exactly that, on the sphere in every direction, on the cylinder across its axis)."""
    tan = math.tan(math.radians(angle))
    return depth_texels * ratio * (tan ** 3 / 2.0 + tan)


def first_order_limit(angle: float, depth_texels: float, budget: float) -> float:
    """The S/R at which :func:`first_order` reaches ``budget`` texels."""
    return budget / first_order(angle, depth_texels, 1.0)


#: The angle ranges the report gives the measured p95 over the rule for (second-order terms grow with the angle).
ANGLE_RANGES = ((30.0, 60.0), (70.0, 85.0))


def rule_ratios(rows: list[dict], surface: str, heightmap: str, angles: tuple[float, float]) -> tuple[float, float]:
    """The smallest and largest measured p95 over :func:`first_order` on ``heightmap`` and ``surface`` where S/R is
    at most LINEAR_UP_TO and no ray is lost, in the angle range ``angles``; NaNs without such rows."""
    q = [r["err_p95"] / first_order(r["angle"], r["depth_texels"], r["s_over_r"]) for r in rows
         if (r["surface"], r["heightmap"]) == (surface, heightmap) and r["s_over_r"] <= LINEAR_UP_TO
         and angles[0] <= r["angle"] <= angles[1] and r["angle"] > 0 and r["curved_miss"] == 0
         and np.isfinite(r["err_p95"])]
    return (min(q), max(q)) if q else (math.nan, math.nan)


def _slope(rows: list[dict], surface: str) -> float:
    slopes = []
    groups = {(r["heightmap"], r["height_scale"], r["angle"]) for r in rows if r["surface"] == surface}
    for key in groups:
        mine = sorted((r["s_over_r"], r["err_p95"]) for r in rows if r["surface"] == surface
                      and (r["heightmap"], r["height_scale"], r["angle"]) == key and r["s_over_r"] <= LINEAR_UP_TO
                      and np.isfinite(r["err_p95"]) and r["err_p95"] > 0 and r["curved_miss"] == 0)
        if len(mine) >= 2:
            slopes.append(np.polyfit(np.log([m[0] for m in mine]), np.log([m[1] for m in mine]), 1)[0])
    return float(np.median(slopes)) if slopes else math.nan


def measured_limit(rows: list[dict], surface: str, height_scale: float, angle: float, budget: float) -> float | None:
    """The largest measured S/R up to which p95 stays within ``budget`` texels and no ray is lost, on every map
    (log-interpolated to where the worst map crosses the budget); None when the smallest S/R already fails or there
    is no row; math.inf when even the largest passes."""
    mine = [r for r in rows if (r["surface"], r["height_scale"], r["angle"]) == (surface, height_scale, angle)]
    ratios = sorted({r["s_over_r"] for r in mine})
    if not ratios:
        return None
    worst = []
    for ratio in ratios:
        at = [r for r in mine if r["s_over_r"] == ratio]
        bad = any(r["curved_miss"] > 0 or not np.isfinite(r["err_p95"]) for r in at)
        worst.append(math.inf if bad else max(r["err_p95"] for r in at))
    if worst[0] > budget:
        return None
    for i in range(1, len(ratios)):
        if worst[i] > budget:
            if math.isinf(worst[i]) or worst[i - 1] <= 0:
                return ratios[i - 1]
            f = math.log(budget / worst[i - 1]) / math.log(worst[i] / worst[i - 1])
            return math.exp(math.log(ratios[i - 1]) + f * math.log(ratios[i] / ratios[i - 1]))
    return math.inf


# --- outputs -----------------------------------------------------------------------------------------------------

PLOT_ERROR = "error_vs_ratio.png"
PLOT_RULE = "rule.png"


def _write(out: Path, rows: list[dict], header: Header) -> None:
    TABLE.write(out / "results.csv", rows)
    plotted = plot([r for r in rows if r["tracer"] == EXACT], out)
    write_bytes(out / "report.md", report(rows, header, plotted).encode())


def plot(rows: list[dict], out: Path) -> bool:
    """error_vs_ratio.png (p95 against S/R, log-log, one line per angle; one panel per map and surface at the
    largest height scale) and rule.png (the normalised error against the angle with the fitted rule); False when
    matplotlib is missing."""
    with pyplot() as plt:
        if plt is None:
            return False
        _draw_error(plt, rows, out / PLOT_ERROR)
        _draw_rule(plt, rows, out / PLOT_RULE)
    return True


def _draw_error(plt, rows: list[dict], path: Path) -> None:
    scale = max(r["height_scale"] for r in rows)
    shown = [r for r in rows if r["height_scale"] == scale]
    maps = list(dict.fromkeys(r["heightmap"] for r in shown))
    surfaces = list(dict.fromkeys(r["surface"] for r in shown))
    angles = sorted({r["angle"] for r in shown if r["angle"] > 0})
    fig, axes = plt.subplots(len(surfaces), len(maps), figsize=(2.9 * len(maps), 2.7 * len(surfaces)),
                             squeeze=False, sharex=True, sharey=True)
    for row_axes, surface in zip(axes, surfaces):
        for ax, name in zip(row_axes, maps):
            for i, angle in enumerate(angles):
                mine = sorted((r["s_over_r"], r["err_p95"], r["curved_miss"]) for r in shown
                              if (r["heightmap"], r["surface"], r["angle"]) == (name, surface, angle))
                x = [m[0] for m in mine if np.isfinite(m[1]) and m[1] > 0]
                y = [m[1] for m in mine if np.isfinite(m[1]) and m[1] > 0]
                color = plt.cm.viridis(i / max(len(angles) - 1, 1))
                ax.loglog(x, y, "-o", ms=2.5, lw=1.1, color=color, label=f"{angle:g}°")
                lost = [(m[0], m[1]) for m in mine if m[2] > 0 and np.isfinite(m[1]) and m[1] > 0]
                if lost:  # rays lost at the silhouette: the error of the rest only
                    ax.loglog(*zip(*lost), "x", ms=6, color=color)
            ax.axhline(0.5, color="red", lw=0.8, ls="--")
            ax.set_title(f"{name}, {surface}", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(which="both")
    for ax in axes[-1]:
        ax.set_xlabel("S/R", fontsize=7)
    for ax in axes[:, 0]:
        ax.set_ylabel("p95 error (texels)", fontsize=7)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=7, frameon=False)
    fig.suptitle(f"Tangent-plane hit vs curved hit, p95 (S = {scale:g} UV; x: some rays lost at the silhouette; "
                 f"red: 0.5 texel)", fontsize=9)
    fig.tight_layout(rect=(0, 0.05, 1, 0.95))
    save_png(fig, path, tight=False)


def _draw_rule(plt, rows: list[dict], path: Path) -> None:
    surfaces = list(dict.fromkeys(r["surface"] for r in rows))
    maps = list(dict.fromkeys(r["heightmap"] for r in rows))
    fig, axes = plt.subplots(1, len(surfaces), figsize=(4.6 * len(surfaces), 3.6), squeeze=False)
    for ax, surface in zip(axes[0], surfaces):
        for i, name in enumerate(maps):
            mine = [(r["angle"], r["err_p95"] / (r["depth_texels"] * r["s_over_r"])) for r in rows
                    if (r["surface"], r["heightmap"]) == (surface, name) and r["s_over_r"] <= LINEAR_UP_TO
                    and r["angle"] > 0 and r["curved_miss"] == 0 and np.isfinite(r["err_p95"]) and r["err_p95"] > 0]
            if mine:
                ax.semilogy(*zip(*mine), ".", ms=4, alpha=0.6, color=plt.cm.tab10(i % 10), label=name)
        a = np.linspace(1.0, 85.0, 100)
        ax.semilogy(a, [first_order(x, 1.0, 1.0) for x in a], "k-", lw=1.2, label="tan³θ/2 + tanθ")
        ax.set_title(surface, fontsize=9)
        ax.set_xlabel("view angle to the normal (deg)", fontsize=8)
        ax.set_ylabel("p95 / (depth_texels · S/R)", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(which="both")
        ax.legend(fontsize=7)
    fig.suptitle(f"The rule: p95 ≈ (S · texels per tile) · S/R · (tan³θ/2 + tanθ) for hits at full depth (S/R ≤ "
                 f"{LINEAR_UP_TO:g}, every S)", fontsize=9)
    fig.tight_layout()
    save_png(fig, path, tight=False)


def _ratio(value: float | None) -> str:
    if value is None:
        return "< smallest"
    return "≥ largest" if math.isinf(value) else f"{value:.2g}"


def report(all_rows: list[dict], header: Header, plotted: bool) -> str:
    """Markdown: the rule per surface, the S/R limits per angle (measured, worst map), then per surface and height
    scale the p95 error (worst map) by angle (rows) and S/R (columns) and the rays lost at the silhouette; then the
    techniques against the curved truth."""
    rows = [r for r in all_rows if r["tracer"] == EXACT]
    lines = [*header.lines(), "",
             "Error: texels between the tangent-plane hit (the flat float64 exact hit: what a perfect relief technique "
             "computes) and the exact hit on the height field displaced inward on the curved surface, wrap-aware, "
             "over the rays where both hit. Lost: rays the curved surface loses at its silhouette (the tangent "
             "plane hits). " + (f"Plots: [{PLOT_ERROR}]({PLOT_ERROR}), [{PLOT_RULE}]({PLOT_RULE})." if plotted
                                else MISSING), ""]
    surfaces = list(dict.fromkeys(r["surface"] for r in rows))
    scales = sorted({r["height_scale"] for r in rows}, reverse=True)
    angles = sorted({r["angle"] for r in rows})
    ratios = sorted({r["s_over_r"] for r in rows})
    maps = ", ".join(dict.fromkeys(f"{r['heightmap']} {r['size']}" for r in rows))
    lines += [f"Height maps: {maps}; {rows[0]['rays'] if rows else 0} rays per map, angle and S/R (uniform entry "
              "points, random azimuths).", "", "## The rule", ""]
    lines += ["p95 ≈ κ · depth_texels · S/R · (tan³θ/2 + tanθ), depth_texels = S × texels per tile, κ ≤ 1 the "
              "squared depth the hits lie at (first order in S/R; `first_order`). Measured p95 over the rule "
              f"(κ with the second-order terms), S/R ≤ {LINEAR_UP_TO:g}, every S:", "",
              "| surface | map | " + " | ".join(f"{a:g}–{b:g}°" for a, b in ANGLE_RANGES) + " | log-log slope |",
              "|---|---|" + "---|" * (len(ANGLE_RANGES) + 1)]
    for surface in surfaces:
        slope = _slope(rows, surface)
        slope_text = "–" if math.isnan(slope) else f"{slope:.2f}"
        for name in dict.fromkeys(r["heightmap"] for r in rows):
            cells = [rule_ratios(rows, surface, name, span) for span in ANGLE_RANGES]
            lines.append(f"| {surface} | {name} | " + " | ".join(
                "–" if math.isnan(lo) else f"{lo:.2f}–{hi:.2f}" for lo, hi in cells) + f" | {slope_text} |")
    lines += ["", "The rule's S/R for a p95 of 0.5 texel with κ = 1: " + "; ".join(
        f"{d:g} texels deep: " + ", ".join(f"{a:g}° {first_order_limit(a, d, 0.5):.2g}" for a in (30, 45, 60, 75, 85))
        for d in sorted({r["depth_texels"] for r in rows}, reverse=True)) + "."]
    lines += ["", "## Limits: the largest S/R within a p95 budget with no ray lost (measured, worst map)", ""]
    for scale in scales:
        depth_texels = max(r["depth_texels"] for r in rows if r["height_scale"] == scale)
        lines += [f"S = {scale:g} UV ({depth_texels:g} texels deep):", "",
                  "| surface | budget | " + " | ".join(f"{a:g}°" for a in angles) + " |",
                  "|---|---|" + "---|" * len(angles)]
        for surface in surfaces:
            for budget in BUDGETS:
                cells = [_ratio(measured_limit(rows, surface, scale, a, budget)) for a in angles]
                lines.append(f"| {surface} | {budget:g} texel | " + " | ".join(cells) + " |")
        lines.append("")
    for surface in surfaces:
        for scale in scales:
            mine = [r for r in rows if (r["surface"], r["height_scale"]) == (surface, scale)]
            lines += [f"## {surface}, S = {scale:g}: p95 error in texels, worst map (lost rays, worst map)", "",
                      "| angle | " + " | ".join(f"S/R {x:g}" for x in ratios) + " |", "|---|" + "---|" * len(ratios)]
            for angle in angles:
                cells = []
                for ratio in ratios:
                    at = [r for r in mine if (r["angle"], r["s_over_r"]) == (angle, ratio)]
                    if not at:
                        cells.append("-")
                        continue
                    p95 = [r["err_p95"] for r in at if np.isfinite(r["err_p95"])]
                    lost = max(r["curved_miss"] for r in at)
                    text = f"{max(p95):.3g}" if p95 else "–"
                    cells.append(text + (f" ({100 * lost:.0f} % lost)" if lost > 0 else ""))
                lines.append(f"| {angle:g}° | " + " | ".join(cells) + " |")
            lines.append("")
    return "\n".join(lines + _technique_lines(all_rows)) + "\n"


def _technique_lines(rows: list[dict]) -> list[str]:
    """Per technique, surface and height scale: its p95 against the curved truth (worst map) by angle and S/R, with
    its own p95 against the flat exact hit (the S/R = inf column) and the tangent plane's (the curvature term)."""
    names = list(dict.fromkeys(r["tracer"] for r in rows if r["tracer"] != EXACT))
    if not names:
        return []
    lines = ["## Techniques against the curved truth", "",
             "p95 in texels, worst map, on the same rays (default parameters, the GPU probe): the technique's hit "
             "against the curved exact hit; *own*: against the flat exact hit (its error on a flat surface); in "
             "brackets the tangent plane's own p95 against the curved hit (the curvature term alone).", ""]
    for name in names:
        for surface in dict.fromkeys(r["surface"] for r in rows):
            for scale in sorted({r["height_scale"] for r in rows}, reverse=True):
                mine = [r for r in rows if (r["tracer"], r["surface"], r["height_scale"]) == (name, surface, scale)]
                exact = {(r["heightmap"], r["angle"], r["s_over_r"]): r for r in rows
                         if (r["tracer"], r["surface"], r["height_scale"]) == (EXACT, surface, scale)}
                ratios = sorted({r["s_over_r"] for r in mine})
                lines += [f"### `{name}`, {surface}, S = {scale:g}", "",
                          "| angle | own | " + " | ".join(f"S/R {x:g}" for x in ratios) + " |",
                          "|---|---|" + "---|" * len(ratios)]
                for angle in sorted({r["angle"] for r in mine}):
                    own = max(r["own_p95"] for r in mine if r["angle"] == angle)
                    cells = []
                    for ratio in ratios:
                        at = [r for r in mine if (r["angle"], r["s_over_r"]) == (angle, ratio)
                              and np.isfinite(r["err_p95"])]
                        if not at:
                            cells.append("–")
                            continue
                        worst = max(at, key=lambda r: r["err_p95"])
                        curvature = exact[(worst["heightmap"], angle, ratio)]["err_p95"]
                        cells.append(f"{worst['err_p95']:.3g} ({curvature:.3g})")
                    lines.append(f"| {angle:g}° | {own:.3g} | " + " | ".join(cells) + " |")
                lines.append("")
    return lines
