"""The perspective study's plots (``report.PLOTS`` lists them): error against span length, tilt and coordinate
magnitude, along one long span, against cost, the drift's heat map and the relief tie-back."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wgpuviewer.harness.plots import pyplot, save_png

from .methods import METHODS
from .report import MITIGATIONS, PAPER_F32, REFERENCE_F32, first_row, select_rows, single_precision


def write_plots(out: Path, rows: list[dict], along: list[dict], relief: list[dict], heat: dict) -> bool:
    """Every plot of ``report.PLOTS`` into ``out``; False (and none) without matplotlib."""
    with pyplot() as plt:
        if plt is None:
            return False
        plot_sweep(plt, rows, "span_length", "span_length", out / "error_vs_span_length.png", "span length (pixels)",
                   True, "Float32 error against span length")
        plot_along(plt, along, out / "error_along_span.png")
        plot_sweep(plt, rows, "tilt", "tilt_deg", out / "error_vs_tilt.png", "angle at the span's far end (degrees)",
                   False, "Float32 error against tilt: in texels, and in pixels of the footprint there",
                   values=("max_err", "max_err_px"))
        plot_sweep(plt, rows, "magnitude", "coord_max_texels", out / "error_vs_magnitude.png",
                   "largest texture coordinate in the frame (texels)", True,
                   "Float32 error against coordinate magnitude")
        plot_pareto(plt, rows, out / "pareto.png")
        plot_heatmap(plt, heat, out / "drift_heatmap.png")
        plot_tieback(plt, relief, out / "tieback.png")
    return True


def _style(name: str) -> dict:
    if name == "hardware":
        return {"color": "black", "linestyle": "-", "linewidth": 2.2, "marker": "s", "markersize": 4}
    family = METHODS[name].family
    return {"linestyle": {"paper": "-", "reference": ":", "mitigation": "--"}[family], "marker": "o", "markersize": 3}


VALUE_LABELS = {"max_err": "max texture-coordinate error (texels)",
                "max_err_px": "max error / the pixel's texel footprint (pixels)"}


def plot_sweep(plt, rows, sweep: str, key: str, path: Path, xlabel: str, logx: bool, title: str,
               values=("max_err",)) -> None:
    groups = [("the paper's forms (float32)", PAPER_F32 + ["hardware"]),
              ("subdivided and mitigations (float32)", ["incremental", *REFERENCE_F32, *MITIGATIONS])]
    fig, axes = plt.subplots(len(values), 2, figsize=(13, 4.8 * len(values)), sharey="row", squeeze=False)
    for line, value in zip(axes, values):
        for ax, (label, methods) in zip(line, groups):
            for m in methods:
                pts = sorted((r[key], r[value]) for r in select_rows(rows, sweep=sweep, method=m, precision=single_precision(m))
                             if isinstance(r[value], float) and r[value] > 0)
                if pts:
                    ax.plot(*zip(*pts), label=m, **_style(m))
            ax.set_yscale("log")
            if logx:
                ax.set_xscale("log")
                if key == "span_length":  # label lengths people know (1080p and 4K rows), not powers of ten
                    from matplotlib.ticker import NullFormatter

                    lengths = {r[key] for r in select_rows(rows, sweep=sweep)}
                    marks = sorted(lengths & {64, 256, 1024, 1920, 3840, 8192, 16384}) or sorted(lengths)
                    ax.set_xticks(marks, [str(int(n)) for n in marks], fontsize=8)
                    ax.xaxis.set_minor_formatter(NullFormatter())
            ax.set_xlabel(xlabel)
            ax.set_title(label)
            ax.grid(True, which="both", )
            ax.legend(fontsize=7, ncol=2)
        line[0].set_ylabel(VALUE_LABELS[value])
    fig.suptitle(title)
    save_png(fig, path)


def plot_along(plt, along: list[dict], path: Path) -> None:
    fig, ax = plt.subplots(figsize=(8, 4.8))
    for m in ["incremental", "parallel_2", "parallel_8", "parallel_32", "two_ended", "direct", "kahan", "hardware"]:
        pts = [((r["n_start"] + r["n_end"]) / 2, r["max_err"]) for r in along
               if r["method"] == m and r["precision"] == single_precision(m) and r["max_err"] > 0]
        if pts:
            ax.plot(*zip(*pts), label=m, **_style(m))
    ax.set_yscale("log")
    ax.set_xlabel("position along the span n (pixels)")
    ax.set_ylabel("max error in the bin (texels)")
    length = along[0]["span_length"] if along else 0
    ax.set_title(f"Where the float32 error builds up along a {int(length)}-pixel span")
    ax.grid(True, which="both", )
    ax.legend(fontsize=8)
    save_png(fig, path)


def plot_pareto(plt, rows, path: Path) -> None:
    speed = select_rows(rows, sweep="speed")
    if not speed:
        return
    w, h = speed[0]["span_length"], speed[0]["spans"]
    here = [r for r in speed if (r["span_length"], r["spans"]) == (w, h)]
    fig, axes = plt.subplots(1, 2, figsize=(13, 5), sharey=True)
    for ax, key, label in ((axes[0], "gpu_ratio", "GPU time × direct"), (axes[1], "cpu_ratio", "CPU (numpy) time × direct")):
        for r in here:
            if not isinstance(r[key], float) or not r["max_err"] > 0:
                continue
            style = _style(r["method"])
            ax.scatter(r[key], r["max_err"], color=style.get("color"), marker=style["marker"], s=30)
            ax.annotate(r["method"], (r[key], r["max_err"]), fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(label)
        ax.grid(True, which="both", )
    axes[0].set_ylabel("max error (texels)")
    fig.suptitle(f"Error against cost: {int(h)} spans of {int(w)} pixels, tilt {here[0]['tilt_deg']:g}°")
    save_png(fig, path)


def plot_heatmap(plt, heat: dict, path: Path) -> None:
    from matplotlib.colors import LogNorm

    ref = heat["reference"]
    checker = (np.floor(ref.u / 32) + np.floor(ref.v / 32)) % 2
    picture = np.where(ref.valid, 0.35 + 0.5 * checker, 0.05)
    errors = [heat["incremental"], heat["direct"]]
    top = max(float(np.nanmax(e)) for e in errors)
    norm = LogNorm(vmin=max(top * 1e-5, 1e-6), vmax=top)
    fig, axes = plt.subplots(3, 1, figsize=(9, 11), layout="constrained")
    axes[0].imshow(picture, cmap="gray", vmin=0, vmax=1, interpolation="nearest")
    axes[0].set_title("the quad: a 32-texel checker at the float64 uv, unfiltered (black: past the horizon)")
    for ax, err, name in zip(axes[1:], errors, ("incremental", "direct")):
        image = ax.imshow(err, cmap="inferno", norm=norm, interpolation="nearest")
        ax.set_title(f"{name}, float32: texel error (max {np.nanmax(err):.3g}); each row is a span, left to right")
    fig.colorbar(image, ax=list(axes), label="texels (black: below the scale or not compared)", shrink=0.6)
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
        for variant, style in (("raw", "-"), ("shader_fract", "--")):
            pts = [(r["magnitude_uv"], r["p99_err"]) for r in relief
                   if r["technique"] == t and r["variant"] == variant and r["magnitude_uv"] > 0]
            ax.plot(*zip(*sorted(pts)), style, marker="o", markersize=3, label=f"{t} ({variant})")
    spacing = [first_row(relief, magnitude_uv=m)["input_spacing_texels"] for m in mags]
    ax.plot(mags, spacing, ":", color="black", label="float32 spacing of the uv")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("texture coordinate magnitude (UV units; the texture spans 1)")
    ax.set_ylabel("p99 hit-uv error (texels)")
    ax.set_title(f"Relief techniques at large uv ({int(relief[0]['texels'])}² map, {relief[0]['angle_deg']:g}°)")
    ax.grid(True, which="both", )
    ax.legend(fontsize=7)
    save_png(fig, path)
