"""The perspective study's plots (``report.PLOTS`` lists them): error against span length, tilt and coordinate
magnitude, along one long span, the approximations against tilt, error against cost, the drift's heat map and the
relief tie-back. Errors are in screen pixels (texels in a second row where the texture's scale matters)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wgpuviewer.lab.harness.plots import pyplot, save_png

from .methods import METHODS
from .selection import (
    APPROXIMATIONS,
    MITIGATIONS,
    PAPER_F32,
    RECIPROCAL,
    first_row,
    select_rows,
    single_precision,
    speed_frames,
)

HORIZON = 90.0  # degrees: from here on a span reaches the wall's horizon (its undefined pixels are flagged)


def write_plots(out: Path, rows: list[dict], along: list[dict], relief: list[dict], heat: dict) -> bool:
    """Every plot of ``report.PLOTS`` into ``out``; False (and none) without matplotlib."""
    with pyplot() as plt:
        if plt is None:
            return False
        plot_sweep(plt, rows, "span_length", "span_length", out / "error_vs_span_length.png", "span length (pixels)",
                   True, "Float32 error against span length, a texel per pixel at the frame's middle")
        plot_along(plt, along, out / "error_along_span.png")
        plot_sweep(plt, rows, "tilt", "tilt_deg", out / "error_vs_tilt.png", "angle at the span's far end (degrees)",
                   False, "Float32 error against tilt (hollow, shaded: at or past the horizon; flagged pixels left out)")
        plot_sweep(plt, rows, "magnitude", "coord_max_texels", out / "error_vs_magnitude.png",
                   "largest texture coordinate in the frame (texels)", True,
                   "Float32 error against coordinate magnitude")
        plot_approximations(plt, rows, out / "approximations.png")
        plot_pareto(plt, rows, out / "pareto.png")
        plot_heatmap(plt, heat, out / "drift_heatmap.png")
        plot_tieback(plt, relief, out / "tieback.png")
    return True


def _style(name: str) -> dict:
    if name == "hardware":
        return {"color": "black", "linestyle": "-", "linewidth": 2.2, "marker": "s", "markersize": 4}
    family = METHODS[name].family
    return {"linestyle": {"paper": "-", "reciprocal": "-.", "approximation": ":", "mitigation": "--"}[family],
            "marker": "o", "markersize": 3}


VALUE_LABELS = {"max_err_px": "worst pixel's error (screen pixels)",
                "max_err": "worst pixel's error (texels)"}


def _points(rows, sweep: str, key: str, method: str, value: str) -> list[tuple[float, float, float]]:
    """(x, error, tilt) of ``method``'s rows in ``sweep``, errors > 0 only (a log axis)."""
    return sorted((r[key], r[value], r["tilt_deg"]) for r in select_rows(rows, sweep=sweep, method=method,
                                                                         precision=single_precision(method))
                  if isinstance(r[value], float) and r[value] > 0)


def plot_sweep(plt, rows, sweep: str, key: str, path: Path, xlabel: str, logx: bool, title: str,
               values=("max_err_px", "max_err")) -> None:
    """Two groups of methods side by side; a row per value (pixels, then texels). Points at or past the horizon
    are drawn hollow and unconnected over a shaded band: their undefined pixels are flagged and left out, so the
    error there is over fewer pixels and not comparable with the rest of the line."""
    groups = [("the paper's forms and one-reciprocal variants (float32)", PAPER_F32 + RECIPROCAL + ["hardware"]),
              ("approximations and mitigations (float32)", ["incremental", *APPROXIMATIONS, *MITIGATIONS])]
    fig, axes = plt.subplots(len(values), 2, figsize=(13, 4.8 * len(values)), sharey="row", squeeze=False)
    for line, value in zip(axes, values):
        for ax, (label, methods) in zip(line, groups):
            ax.set_prop_cycle(color=plt.cm.tab20.colors)  # a colour per method: up to 16 lines a panel
            for m in methods:
                pts = _points(rows, sweep, key, m, value)
                before = [(x, e) for x, e, t in pts if t < HORIZON]
                past = [(x, e) for x, e, t in pts if t >= HORIZON]
                if before:
                    (drawn,) = ax.plot(*zip(*before), label=m, **_style(m))
                    color = drawn.get_color()
                else:
                    color = _style(m).get("color")
                if past:
                    ax.scatter(*zip(*past), facecolors="none", edgecolors=color, marker=_style(m)["marker"], s=28)
            if key == "tilt_deg":
                ax.axvspan(HORIZON, max(r[key] for r in select_rows(rows, sweep=sweep)) + 1, color="0.85", zorder=0)
            ax.set_yscale("log")
            if logx:
                ax.set_xscale("log")
                if key == "span_length":  # label lengths people know (tiles, 1080p and 4K rows), not powers of ten
                    from matplotlib.ticker import NullFormatter

                    lengths = {r[key] for r in select_rows(rows, sweep=sweep)}
                    marks = sorted(lengths & {8, 64, 256, 1024, 1920, 3840, 8192, 16384}) or sorted(lengths)
                    ax.set_xticks(marks, [str(int(n)) for n in marks], fontsize=8)
                    ax.xaxis.set_minor_formatter(NullFormatter())
            ax.set_xlabel(xlabel)
            ax.set_title(label, fontsize=10)
            ax.grid(True, which="both")
            ax.legend(fontsize=7, ncol=2)
        line[0].set_ylabel(VALUE_LABELS[value])
    fig.suptitle(title)
    save_png(fig, path)


def plot_along(plt, along: list[dict], path: Path) -> None:
    fig, ax = plt.subplots(figsize=(8, 4.8))
    for m in ["incremental", "parallel_2", "parallel_8", "parallel_32", "two_ended", "direct", "kahan", "hardware"]:
        pts = [((r["n_start"] + r["n_end"]) / 2, r["max_err_px"]) for r in along
               if r["method"] == m and r["precision"] == single_precision(m) and r["max_err_px"] > 0]
        if pts:
            ax.plot(*zip(*pts), label=m, **_style(m))
    ax.set_yscale("log")
    ax.set_xlabel("position along the span n (pixels)")
    ax.set_ylabel("worst pixel's error in the bin (screen pixels)")
    length = along[0]["span_length"] if along else 0
    ax.set_title(f"Where the float32 error builds up along a {int(length)}-pixel span")
    ax.grid(True, which="both")
    ax.legend(fontsize=8)
    save_png(fig, path)


def plot_approximations(plt, rows, path: Path) -> None:
    """Fixed and adaptive subdivision against tilt: worst pixel's error, and what it costs in exact evaluations."""
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.8))
    for m in APPROXIMATIONS:
        style = _style(m) | {"linestyle": "-" if m.startswith("adaptive") else ":"}
        for ax, value in zip(axes, ("max_err_px", "exact_per_pixel")):
            pts = _points(rows, "tilt", "tilt_deg", m, value)
            before = [(x, e) for x, e, t in pts if t < HORIZON]
            if before:
                ax.plot(*zip(*before), label=m, **style)
    for ax, label in zip(axes, ("worst pixel's error (screen pixels)", "exact evaluations per pixel")):
        ax.set_yscale("log")
        ax.set_xlabel("angle at the span's far end (degrees, before the horizon)")
        ax.set_ylabel(label)
        ax.grid(True, which="both")
        ax.legend(fontsize=8)
    length = next((r["span_length"] for r in select_rows(rows, sweep="tilt")), 0)
    fig.suptitle(f"Linear between exact anchors, L = {int(length)}: every S pixels, or as far as the error bound allows")
    save_png(fig, path)


def plot_pareto(plt, rows, path: Path) -> None:
    frames = speed_frames(rows)
    if not frames:
        return
    w, h = frames[0]
    here = select_rows(rows, sweep="speed", span_length=w, spans=h)
    fig, axes = plt.subplots(1, 3, figsize=(17, 5), sharey=True)
    for ax, key, label in ((axes[0], "scalar_ratio", "compiled scalar loop, time × direct"),
                           (axes[1], "simd_ratio", "compiled SIMD build, time × direct"),
                           (axes[2], "gpu_ratio", "GPU adapter (software adapters: on the CPU), time × direct")):
        for r in here:
            if not isinstance(r[key], float) or not r["max_err_px"] > 0:
                continue
            style = _style(r["method"])
            ax.scatter(r[key], r["max_err_px"], color=style.get("color"), marker=style["marker"], s=30)
            ax.annotate(r["method"], (r[key], r["max_err_px"]), fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(label)
        ax.grid(True, which="both")
    axes[0].set_ylabel("worst pixel's error (screen pixels)")
    direct = first_row(here, method="direct")
    fig.suptitle(f"Error against cost: {int(h)} spans of {int(w)} pixels, tilt {direct['tilt_deg']:g}°")
    save_png(fig, path)


def plot_heatmap(plt, heat: dict, path: Path) -> None:
    from matplotlib.colors import LogNorm

    ref = heat["reference"]
    checker = (np.floor(ref.u / 32) + np.floor(ref.v / 32)) % 2
    picture = np.where(ref.valid, 0.35 + 0.5 * checker, 0.05)
    errors = [heat["incremental"], heat["direct"]]
    top = max(float(np.nanmax(e)) for e in errors)
    norm = LogNorm(vmin=max(top * 1e-5, 1e-9), vmax=top)
    fig, axes = plt.subplots(3, 1, figsize=(9, 11), layout="constrained")
    axes[0].imshow(picture, cmap="gray", vmin=0, vmax=1, interpolation="nearest")
    axes[0].set_title("the quad: a 32-texel checker at the float64 uv, unfiltered (black: past the horizon)")
    for ax, err, name in zip(axes[1:], errors, ("incremental", "direct")):
        image = ax.imshow(err, cmap="inferno", norm=norm, interpolation="nearest")
        ax.set_title(f"{name}, float32: error in screen pixels (max {np.nanmax(err):.3g}); each row is a span, "
                     f"left to right")
    fig.colorbar(image, ax=list(axes), label="screen pixels (black: below the scale or not compared)", shrink=0.6)
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    s = heat["setup"]
    fig.suptitle(f"Float32 drift on a long grazing quad: {s.span_length}×{s.rows}, tilt {s.tilt:g}° at the far end")
    save_png(fig, path)


def plot_tieback(plt, relief: list[dict], path: Path) -> None:
    if not relief:
        return
    fig, ax = plt.subplots(figsize=(8, 5))
    mags = sorted({r["magnitude_uv"] for r in relief if r["magnitude_uv"] > 0})
    for t in dict.fromkeys(r["technique"] for r in relief):
        pts = [(r["magnitude_uv"], r["p99_err"]) for r in relief if r["technique"] == t and r["magnitude_uv"] > 0]
        ax.plot(*zip(*sorted(pts)), "-", marker="o", markersize=3, label=t)
    spacing = [first_row(relief, magnitude_uv=m)["input_spacing_texels"] for m in mags]
    ax.plot(mags, spacing, ":", color="black", label="float32 spacing of the uv")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("texture coordinate magnitude (UV units; the texture spans 1)")
    ax.set_ylabel("p99 hit-uv error (texels)")
    ax.set_title(f"Relief techniques at large uv ({int(relief[0]['texels'])}² map, {relief[0]['angle_deg']:g}°)")
    ax.grid(True, which="both")
    ax.legend(fontsize=7)
    save_png(fig, path)
