"""The benchmark's plots (run.py draws them beside report.md): the Pareto front of time against error per height
map, fetches against the view angle, and which cost predicts the time."""

from __future__ import annotations

import math
from collections import defaultdict
from pathlib import Path

import numpy as np

from wgpuviewer.lab.harness.plots import MISSING, pyplot, save_png

from .report import config_key, config_label, cost_correlation

DPI = 72  # small files (the committed runs keep their pictures in the repository)


def pareto_front(points: list[tuple[float, float]]) -> list[int]:
    """Indices of the points no other point beats in both x and y (lower is better), by x."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best_y = [], math.inf
    for i in order:
        if points[i][1] < best_y:
            front.append(i)
            best_y = points[i][1]
    return front


def plots(out: Path, values: list[dict]) -> tuple[list[str], str | None]:
    """The plots of ``values`` (results rows) into ``out``: their file names, and the note the report shows instead
    when matplotlib is missing."""
    with pyplot() as plt:
        if plt is None:
            return [], MISSING
        return _draw(plt, Path(out), values), None


def _draw(plt, out: Path, values: list[dict]) -> list[str]:
    written = []
    maps = list(dict.fromkeys(v["heightmap"] for v in values))
    techniques = list(dict.fromkeys(v["technique"] for v in values))
    # one colour per technique (tab20 once there are more than ten), one line style per configuration of it
    palette = plt.cm.tab10 if len(techniques) <= 10 else plt.cm.tab20
    colors = {t: palette(i % palette.N) for i, t in enumerate(techniques)}
    floor = 1e-3  # p95 of 0 drawn at this value on the log axis

    cols = min(3, len(maps)) or 1
    rows_n = max(1, math.ceil(len(maps) / cols))
    fig, axes = plt.subplots(rows_n, cols, figsize=(4.2 * cols, 3.4 * rows_n), squeeze=False)
    for ax, m in zip(axes.ravel(), maps):
        by_config = defaultdict(list)
        for v in values:
            if v["heightmap"] == m:
                by_config[config_key(v)].append(v)
        keys = list(by_config)
        pts = [(float(np.mean([v["ratio_to_basic"] for v in by_config[k]])),
                max(float(np.mean([v["uv_err_p95"] for v in by_config[k]])), floor)) for k in keys]
        for k, (x, y) in zip(keys, pts):
            ax.scatter(x, y, color=colors[k[0]], s=14)
        front = pareto_front(pts)
        ax.plot([pts[i][0] for i in front], [pts[i][1] for i in front], "k--", lw=0.8)
        for n, i in enumerate(sorted(front, key=lambda i: pts[i][0])):
            # neighbours along the front alternate above and below their point, so their labels do not overlap
            ax.annotate(config_label(keys[i]).replace("layers=", ""), pts[i], fontsize=6,
                        xytext=(4, 3 if n % 2 == 0 else -9), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        _plain_ratio_ticks(ax.xaxis, [x for x, _ in pts])
        ax.set_title(m, fontsize=9)
        ax.set_xlabel("GPU time / basic (mean over angles)", fontsize=7)
        ax.set_ylabel("p95 UV error, texels (mean over angles)", fontsize=7)
        ax.tick_params(labelsize=6)
    for ax in axes.ravel()[len(maps):]:
        ax.axis("off")
    handles = [plt.Line2D([], [], marker="o", ls="", color=colors[t], label=t) for t in techniques]
    fig.legend(handles=handles, loc="lower center", ncol=min(len(techniques), 7), fontsize=7)
    fig.tight_layout(rect=(0, 0.04 + 0.035 * math.ceil(len(techniques) / 7), 1, 1))
    written.append(save_png(fig, out / "pareto.png", dpi=DPI))

    fig, ax = plt.subplots(figsize=(10, 4.8))
    by_config = defaultdict(lambda: defaultdict(list))
    for v in values:
        by_config[config_key(v)][v["angle"]].append(v["fetches_mean"])
    styles = ("-", "--", ":", "-.")
    seen = defaultdict(int)
    for k, per_angle in by_config.items():
        angles = sorted(per_angle)
        ax.plot(angles, [np.mean(per_angle[a]) for a in angles], marker=".", color=colors[k[0]],
                ls=styles[seen[k[0]] % len(styles)], lw=0.9, label=config_label(k))
        seen[k[0]] += 1
    ax.set_yscale("symlog", linthresh=1)
    ax.set_xlabel("view angle at the frame centre (degrees)")
    ax.set_ylabel("depth fetches per pixel (mean over height maps)")
    ax.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    written.append(save_png(fig, out / "fetches_vs_angle.png", dpi=DPI))

    c = cost_correlation(values)
    if c["rows"] >= 3:
        rows = [v for v in values if math.isfinite(v.get("fetches_simd", float("nan")))]
        fig, axes = plt.subplots(1, 2, figsize=(10.5, 4), sharey=True)
        for ax, column, title, r in ((axes[0], "fetches_mean", "mean fetches per pixel", c["mean"]),
                                      (axes[1], "fetches_simd", "SIMD-tile fetches", c["simd"])):
            for t in techniques:
                vs = [v for v in rows if v["technique"] == t]
                ax.scatter([v[column] for v in vs], [v["ratio_to_basic"] for v in vs], s=8, color=colors[t], label=t)
            ax.set_xscale("symlog", linthresh=1)
            ax.set_yscale("log")
            ax.set_xlabel(title)
            ax.set_title(f"Pearson r = {r:.3f} (all rows)", fontsize=9)
        axes[0].set_ylabel("time / basic")
        axes[1].legend(fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5))
        fig.tight_layout()
        written.append(save_png(fig, out / "cost_vs_time.png", dpi=DPI))
    return written


def _plain_ratio_ticks(axis, values) -> None:
    """Ticks of a log axis of time ratios as plain numbers (1, 1.5, 2, 3, ...) instead of powers of ten."""
    from matplotlib.ticker import FixedLocator, NullFormatter, NullLocator, ScalarFormatter

    lo, hi = min(values), max(values)
    ticks = [t for t in (1, 1.5, 2, 3, 4, 6, 8, 10, 15, 20, 30, 40, 60, 80, 100) if lo / 1.3 <= t <= hi * 1.3]
    axis.set_major_locator(FixedLocator(ticks or [1]))
    axis.set_major_formatter(ScalarFormatter())
    axis.set_minor_locator(NullLocator())
    axis.set_minor_formatter(NullFormatter())
