"""The study's pictures: the cost ratio of the walk against the cheapest linear search per map and angle (the claim
at a glance), and a Fig. 3-style example pyramid: the paper's 8x8 example heights, the walk's max pyramid over them
(level 0 the bilinear cells' maxima, as the renderer builds it) and one ray's steps on every level, numbered in the
order the twin (twin.py) takes them."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wgpuviewer.lab.harness.plots import pyplot, save_png

from .compare import ratio
from .twin import pyramid, walk

#: The paper's Fig. 3 (Romanyuk & Dudnyk 2018): the example height map under its max pyramid, rows top to bottom.
PAPER_FIG3 = np.array([
    [0.9, 0.8, 0.5, 0.6, 0.8, 0.6, 0.5, 0.6], [0.2, 0.3, 0.2, 0.6, 0.5, 0.7, 0.1, 0.2],
    [0.5, 0.4, 0.5, 0.4, 0.5, 0.4, 0.5, 0.4], [0.3, 0.7, 0.7, 0.3, 0.3, 0.6, 0.7, 0.3],
    [0.3, 0.4, 0.4, 0.5, 0.5, 0.4, 0.4, 0.3], [0.5, 0.2, 0.2, 0.3, 0.5, 0.4, 0.3, 0.2],
    [0.5, 0.4, 0.5, 0.4, 0.5, 0.4, 0.3, 0.2], [0.1, 0.7, 0.7, 0.3, 0.3, 0.7, 0.2, 0.3]])
#: The example ray: its view angle, relief depth (UV) and the candidates it is chosen from (entry uv x azimuth).
EXAMPLE_ANGLE = 60.0
EXAMPLE_SCALE = 0.3
RATIO_PNG = "ratio.png"
PYRAMID_PNG = "pyramid.png"


def example_ray(height: np.ndarray = PAPER_FIG3):
    """(uv, v, walk, ray) of the example: among entry points on a 16x16 grid and 8 azimuths at EXAMPLE_ANGLE, a
    ray whose path stays inside the map's cells (no wrap), visiting the most levels, climbing back up the most, then
    taking the fewest steps (the first such)."""
    from wgpuviewer.relief.reference import view_dir_from_angles

    g = (np.arange(16) + 0.5) / 16
    uu, vv, az = np.meshgrid(g, g, np.arange(8) * 45.0 + 10.0, indexing="ij")
    uv = np.stack([uu.ravel(), vv.ravel()], -1)
    v = view_dir_from_angles(np.full(uv.shape[0], EXAMPLE_ANGLE), az.ravel())
    depth = 1.0 - height.astype(np.float64)
    w = walk(depth, uv, v, EXAMPLE_SCALE, float(depth.min()))
    n = len(uv)
    levels_seen = np.zeros(n, np.int64)
    for m in range(w.top + 1):
        levels_seen += np.bincount(w.step_ray[w.step_level == m], minlength=n) > 0
    same = np.r_[False, w.step_ray[1:] == w.step_ray[:-1]]
    climbs = np.bincount(w.step_ray[same & np.r_[False, w.step_level[1:] > w.step_level[:-1]]], minlength=n)
    cells = uv * 8 - 0.5
    inside = ((cells >= 0) & (cells <= 7) & (w.uv * 8 - 0.5 >= 0) & (w.uv * 8 - 0.5 <= 7)).all(axis=1)
    best = int(np.lexsort((w.fetches, -climbs, -levels_seen, ~inside))[0])  # a ray that does not wrap: drawable
    return uv[best], v[best], w, best


def _pyramid_picture(plt, out: Path) -> str:
    depth = 1.0 - PAPER_FIG3.astype(np.float64)
    atlas, rows = pyramid(depth)
    uv, v, w, ray = example_ray()
    steps = np.flatnonzero(w.step_ray == ray)
    fig, axes = plt.subplots(1, len(rows) + 1, figsize=(3.0 * (len(rows) + 1), 3.4))
    grids = [PAPER_FIG3] + [atlas[rows[m]:rows[m] + max(1, 8 >> m), :max(1, 8 >> m)] for m in range(len(rows))]
    titles = ["the paper's heights"] + [f"walk level {m}" + (" (cell maxima)" if m == 0 else "") for m in
                                        range(len(rows))]
    span = v[:2] / v[2] * EXAMPLE_SCALE * 8
    start = uv * 8 - 0.5
    for k, (ax, grid, title) in enumerate(zip(axes, grids, titles)):
        ax.imshow(grid, cmap="Greys_r", vmin=0, vmax=1, extent=(0, grid.shape[1], grid.shape[0], 0))
        for (y, x), value in np.ndenumerate(grid):
            ax.text(x + 0.5, y + 0.5, f"{value:.1f}", ha="center", va="center", fontsize=7, color="tab:red")
        scale = 1.0 if k == 0 else 1.0 / (1 << (k - 1))
        offset = 0.5 if k == 0 else 0.0  # heights sit at texel centres; the walk's cells start at them
        a, b = (start + offset) * scale, (start + offset - span * w.t[ray]) * scale
        ax.annotate("", xy=tuple(b), xytext=tuple(a), arrowprops={"arrowstyle": "->", "color": "tab:blue"})
        if k:
            for number, s in enumerate(steps, 1):
                if w.step_level[s] == k - 1:
                    x, y = divmod(int(w.step_node[s]), 65536)
                    ax.add_patch(plt.Rectangle((x, y), 1, 1, fill=False, ec="tab:orange", lw=2))
                    ax.text(x + 0.15, y + 0.3, str(number), fontsize=8, color="tab:orange", weight="bold")
        ax.set_title(title, fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(f"One ray ({EXAMPLE_ANGLE:g}°, {w.fetches[ray]} steps, hit at t = {w.t[ray]:.3f}): nodes tested, "
                 "numbered in walk order; arrow: the ray's path to its hit", fontsize=9)
    return save_png(fig, out / PYRAMID_PNG, dpi=80)


def _ratio_picture(plt, rows: list[dict], out: Path) -> str:
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), sharey=True)
    mine = [r for r in rows if r["tracer"] == "maxmip"]
    for ax, criterion, label in zip(axes, ("p95", "max"), ("p95 ≤ 0.25 texel", "max ≤ 1 texel")):
        for name in dict.fromkeys(r["heightmap"] for r in mine):
            pts = sorted((r["angle"], ratio(r, criterion)[0], r["relief_class"]) for r in mine if r["heightmap"] == name)
            flat = pts[0][2].startswith("large")
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "-o" if flat else "--s", ms=3, label=name)
        ax.axhline(1.0, color="k", lw=0.8)
        ax.set_yscale("log")
        ax.set_xlabel("view angle at the frame centre (degrees)")
        ax.set_title(f"equal error: {label}", fontsize=9)
        ax.grid(True, which="both")
    axes[0].set_ylabel("maxmip / cheapest linear search\n(SIMD-tile fetches; < 1: maxmip wins)")
    axes[1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.0, 0.5), title="solid: flat areas")
    return save_png(fig, out / RATIO_PNG, dpi=80)


def draw(rows: list[dict], out: Path) -> list[str]:
    """The pictures written into ``out`` (none without matplotlib); their file names."""
    with pyplot() as plt:
        if plt is None:
            return []
        return [_ratio_picture(plt, rows, out), _pyramid_picture(plt, out)]
