"""A float64 numpy twin of the distance tracer (``wgpuviewer/techniques/distance/distance.wgsl``), for measuring map variants that
no registered technique binds (a single cone, sectors without bands, K = 1 sub-cells) on the very rays the renderer
traces. It takes the same steps and counts the same fetches (tests/lab/studies checks it against the GPU probe): per
iteration one volume fetch; a sphere step when it leaves the current bilinear cell, else the exact solve of that cell
(one gather) and on to the cell's exit. Like the tracer it starts at the map's shallowest depth (``depth_min``, as
``relief.maps.depth_range`` gives it for the uploaded texture): above it the ray meets nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from maptools.kinds.distance_refined.bins import volume_index
from wgpuviewer.relief.reference import cell_root


@dataclass
class Traced:
    t: np.ndarray  # (N,) layer depth of the hit (NaN where the cap stopped the ray)
    fetches: np.ndarray  # (N,) volume fetches + cell gathers
    capped: np.ndarray  # (N,) bool


def trace(depth: np.ndarray, volumes: np.ndarray, uv0, view_dir, height_scale: float, *, sectors: int = 1,
          bands: int = 1, max_angle: float | None = None, iterations: int = 256, depth_min: float = 0.0) -> Traced:
    """Trace rays (uv0 (N, 2), tangent-space V (N, 3), V.z > 0) through ``volumes``: (Dz, H, W) for the plain map, or
    the refined kind's (V, Dz, H, W) with its ``sectors``, ``bands`` and ``max_angle``. ``depth`` = 1 - height;
    ``depth_min``: where the search starts (the tracer's ``relief_range(0).x``)."""
    vol = np.asarray(volumes, np.float64)
    vol = vol[None] if vol.ndim == 3 else vol
    _, slices, vh, vw = vol.shape
    rows, cols = depth.shape
    flat = np.asarray(depth, np.float64).ravel()
    uv0 = np.asarray(uv0, np.float64)
    v = np.asarray(view_dir, np.float64)
    n = len(uv0)
    which = np.zeros(n, np.int64) if max_angle is None else volume_index(v, sectors, bands, max_angle)
    span = v[:, :2] / v[:, 2:3] * height_scale
    size = np.array([cols, rows], np.float64)
    start = uv0 * size - 0.5
    step = -span * size
    per_t = cols * np.sqrt((span ** 2).sum(axis=1) + height_scale ** 2)
    t = np.full(n, min(max(depth_min, 0.0), 1.0))
    t_hit = np.full(n, np.nan)
    fetches = np.zeros(n, np.int64)
    run = np.arange(n)
    for _ in range(iterations):
        if not run.size:
            break
        tr = t[run]
        at = uv0[run] - span[run] * tr[:, None]
        i = np.mod(np.floor(at[:, 0] * cols), vw).astype(np.int64)
        j = np.mod(np.floor(at[:, 1] * rows), vh).astype(np.int64)
        k = np.clip(np.floor(tr * slices), 0, slices - 1).astype(np.int64)
        radius = vol[which[run], k, j, i]
        fetches[run] += 1
        d = step[run]
        cell = np.floor(start[run] + tr[:, None] * d + np.sign(d) * 1e-3)
        with np.errstate(divide="ignore", invalid="ignore"):
            exits = np.where(d > 0, (cell + 1 - start[run]) / d, np.where(d < 0, (cell - start[run]) / d, np.inf))
        t_exit = np.minimum(exits.min(axis=1), 1.0)
        t_sphere = tr + radius / per_t[run]
        sphere = (t_sphere >= t_exit) & (radius > 0)
        t[run[sphere]] = np.minimum(t_sphere[sphere], 1.0)
        solve = run[~sphere]
        fetches[solve] += 1
        c = cell[~sphere].astype(np.int64)
        s = cell_root(flat, rows, cols, c[:, 0], c[:, 1], start[solve, 0], start[solve, 1], step[solve, 0],
                      step[solve, 1], tr[~sphere], np.maximum(t_exit[~sphere], tr[~sphere]))
        hit = ~np.isnan(s)
        t_hit[solve[hit]] = tr[~sphere][hit] + s[hit]
        t[solve[~hit]] = np.maximum(tr[~sphere][~hit], t_exit[~sphere][~hit])
        run = np.concatenate([run[sphere], solve[~hit]])
    capped = np.zeros(n, bool)
    capped[run] = True
    return Traced(t_hit, fetches, capped)
