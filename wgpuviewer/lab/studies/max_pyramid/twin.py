"""A float64 numpy twin of the product's max-pyramid walk (``wgsl/common/maxmip_walk.wgsl``, run by the ``maxmip``
technique), instrumented: the same nodes in the same order, one fetch per step (a pyramid texel above level 0, one
2x2 gather at level 0), the same exact cell solve (``relief.reference.cell_root``), the same cap; besides the hits it
records every step's level and node, from which ``levels`` counts what the paper asserts: steps per level per ray,
the steps taken inside one parent node before the walk leaves it (the paper: at most 2), and the climbs back up.

The pyramid is the renderer's: level 0 the bilinear cells' corner maxima (``cell_max_height``), the coarser levels
maptools' maxmip kind, stacked as the atlas the GPU reads (``maxmip_atlas``). Rays go in as the probe passes them
(the entry uv's integer part removed, then float32), so the twin and the GPU probe start from the same numbers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from maptools.kinds.maxmip.cpu import level_sizes, maxmip
from maptools.kinds.maxmip.slot import cell_max_height, maxmip_atlas
from wgpuviewer.relief.reference import cell_root

#: The GPU's constants (common/maxmip_walk.wgsl, common/trace.wgsl): the skip margin, the smallest view z.
MARGIN = 1e-6
MIN_VIEW_Z = 1e-4
#: maxmip's default step cap (its registry entry).
CAP = 1024


@dataclass
class Walk:
    """The twin's result for N rays, and its steps (one entry per step of any ray)."""

    t: np.ndarray  # (N,) hit depth (the last free point where capped)
    uv: np.ndarray  # (N, 2) hit uv, the entry's integer part added back
    fetches: np.ndarray  # (N,) steps taken = fetches
    capped: np.ndarray  # (N,) bool
    top: int  # the top level
    step_ray: np.ndarray  # (S,) the ray of each step, in step order per ray
    step_level: np.ndarray  # (S,) its level
    step_node: np.ndarray  # (S,) its node (wrapped index at its level, packed x * 65536 + y)
    step_parent: np.ndarray  # (S,) its node's parent (index at level + 1, packed the same way)


def pyramid(depth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(atlas, first atlas row of each level) of the depth map, as the renderer builds and the walk reads them."""
    levels = maxmip(cell_max_height(depth))
    rows = np.cumsum([0] + [h for h, _ in level_sizes(*depth.shape)[:-1]])
    return maxmip_atlas(levels).astype(np.float64), rows.astype(np.int64)


def as_probed(uv: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(fraction of uv, v, integer part of uv) in the precision the probe hands the GPU (float32)."""
    offset = np.floor(uv)
    frac = (uv - offset).astype(np.float32).astype(np.float64)
    return frac, np.asarray(v, np.float32).astype(np.float64), offset


def _box_exit(start, d, lo, hi) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        edge = np.where(d > 0, hi, lo)
        return np.where(d != 0, (edge - start) / d, np.inf)


def walk(depth: np.ndarray, uv, v, height_scale: float, t_from: float, cap: int = CAP) -> Walk:
    """The walk of every ray (uv (N, 2) entry points, v (N, 3) towards the eye) from ``t_from`` (the map's shallowest
    depth as the GPU holds it, ``relief.maps.depth_range``) on ``depth`` (rows, cols), repeat addressing."""
    depth = np.asarray(depth, np.float64)
    atlas, first_row = pyramid(depth)
    top = len(first_row) - 1
    flat, (rows, cols) = depth.ravel(), depth.shape
    wh = np.array([cols, rows], np.int64)
    uv, v, offset = as_probed(np.asarray(uv, np.float64), v)
    n = len(uv)
    span = v[:, :2] / np.maximum(v[:, 2:3], MIN_VIEW_Z) * height_scale
    start, direction = uv * wh - 0.5, -span * wh
    t = np.full(n, float(t_from))
    cell = np.floor(start + t[:, None] * direction).astype(np.int64)
    level = np.full(n, top, np.int64)
    fetches, t_hit = np.zeros(n, np.int64), np.full(n, np.nan)
    active = np.arange(n)
    log_ray, log_level, log_node, log_parent = [], [], [], []
    for _ in range(cap):
        if not active.size:
            break
        c, lv = cell[active], level[active]
        wrapped = np.mod(c, wh)
        index = wrapped >> lv[:, None]
        first = index << lv[:, None]
        lo = c - wrapped + first
        hi = lo + np.minimum(np.left_shift(1, lv)[:, None], wh - first)
        exits = _box_exit(start[active], direction[active], lo, hi)
        t_exit = np.minimum(exits.min(axis=1), 1.0)
        log_ray.append(active)
        log_level.append(lv)
        log_node.append(index[:, 0] * 65536 + index[:, 1])
        log_parent.append((index[:, 0] >> 1) * 65536 + (index[:, 1] >> 1))
        fetches[active] += 1
        coarse = lv > 0
        height = atlas[first_row[lv] + index[:, 1], index[:, 0]]
        descend = coarse & (t_exit >= 1.0 - height - MARGIN)
        s = np.full(len(active), np.nan)
        base = ~coarse
        if base.any():
            a = active[base]
            s[base] = cell_root(flat, rows, cols, c[base, 0], c[base, 1], start[a, 0], start[a, 1], direction[a, 0],
                                direction[a, 1], t[a], t_exit[base])
        hit = base & ~np.isnan(s)
        t_hit[active[hit]] = t[active[hit]] + s[hit]
        level[active[descend]] -= 1
        on = ~descend & ~hit  # nothing in this node: the next one along the ray
        a, t_on = active[on], np.maximum(t[active[on]], t_exit[on])
        t[a] = t_on
        nxt = _next_cell(start[a], direction[a], t_on, exits[on], lo[on], hi[on])
        cell[a] = nxt
        same = ((np.mod(nxt, wh) >> (lv[on] + 1)[:, None]) == (index[on] >> 1)).all(axis=1) & (lv[on] < top)
        level[a] = np.where(same, lv[on], np.minimum(lv[on] + 1, top))
        active = active[~hit]
    capped = np.isnan(t_hit)
    t_hit = np.where(capped, t, t_hit)
    hit_uv = uv - span * t_hit[:, None] + offset
    order = np.argsort(np.concatenate(log_ray), kind="stable") if log_ray else np.zeros(0, np.int64)
    cat = (lambda parts: np.concatenate(parts)[order]) if log_ray else (lambda parts: np.zeros(0, np.int64))
    return Walk(t_hit, hit_uv, fetches, capped, top, cat(log_ray), cat(log_level), cat(log_node),
                cat(log_parent))


def _next_cell(start, d, t_exit, exits, lo, hi) -> np.ndarray:
    """common/cell.wgsl's next_cell: the cell the ray enters on leaving the box [lo, hi) of cells at t_exit."""
    p = np.floor(start + t_exit[:, None] * d).astype(np.int64)
    crossed = exits <= t_exit[:, None]
    inside = np.clip(p, lo, hi - 1)
    return np.where(crossed, np.where(d > 0, hi, lo - 1), inside)


@dataclass
class LevelStats:
    """What the paper asserts about the walk, per level m (0 = the cells, ``top`` = the whole map)."""

    level: int
    steps_per_ray: float  # mean steps (= fetches) at this level per ray
    parent_visits: int  # times the walk entered a node of level m + 1 and took steps at level m inside it
    within_two: float  # of those visits, the share with at most 2 steps at level m (NaN at the top: no parent)
    most_in_parent: int  # the most steps at level m inside one parent visit
    climbs_per_ray: float  # mean climbs from level m to m + 1 per ray


def levels(w: Walk) -> list[LevelStats]:
    """Per-level statistics of a walk's recorded steps. A parent visit at level m is a run of level-m steps of one
    ray under one parent, with only deeper steps between them; a step at a coarser level ends it."""
    n = len(w.fetches)
    ray, lv, parent = w.step_ray, w.step_level, w.step_parent
    same_ray = np.r_[False, ray[1:] == ray[:-1]]
    climbs = np.flatnonzero(same_ray & np.r_[False, lv[1:] > lv[:-1]])
    climbed_from = np.bincount(lv[climbs - 1], minlength=w.top + 1)  # the level each climb leaves
    out = []
    for m in range(w.top + 1):
        steps = int((lv == m).sum())
        climbed = int(climbed_from[m])
        if m == w.top:
            out.append(LevelStats(m, steps / n, 0, float("nan"), 0, climbed / n))
            continue
        keep = lv >= m
        r, l_, k = ray[keep], lv[keep], parent[keep]
        at = l_ == m
        cont = np.r_[False, (r[1:] == r[:-1]) & at[:-1] & at[1:] & (k[1:] == k[:-1])]
        starts = at & ~cont
        run = np.cumsum(starts)[at]
        counts = np.bincount(run)[1:] if run.size else np.zeros(0, np.int64)
        out.append(LevelStats(m, steps / n, int(counts.size), float(np.mean(counts <= 2)) if counts.size else
                              float("nan"), int(counts.max()) if counts.size else 0, climbed / n))
    return out
