"""The paper's visibility condition for the refined kind: the cut per sector and voxel (``horizon``), from the inner
solid's tops over rings of backward distances (cpu.py's docstring states it).
"""

from __future__ import annotations

import math

import numpy as np

from maptools.volume import cpu as dist

from .bins import ANGLE_SLACK, HORIZON_STEP, Bin, bins, wedge_rho

# -- the visibility condition ------------------------------------------------------------------------

def inner_tops(depth: np.ndarray) -> np.ndarray:
    """Top of the inner solid's column over each bilinear cell [i + 0.5, i + 1.5] x [j + 0.5, j + 1.5] (texels): the
    DEEPEST of its four corner depths (the bilinear patch is nowhere deeper), float64 (H, W) at [j, i]."""
    return dist.cell_corners(depth, np.maximum)


def ring_count(reach: float) -> int:
    """Backward distances tested: HORIZON_STEP, 2 HORIZON_STEP, ... up to the reach."""
    return int(math.floor(reach / HORIZON_STEP + 1e-9))


def horizon_rings(b: Bin, sy: float, reach: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per backward distance x = n HORIZON_STEP (n = 1, 2, ... up to the reach): the cell offsets (ox, oy) from a
    voxel's own cell whose cell the voxel's footprint, shifted by -x u for an azimuth u of ``b``'s wedge, can touch.
    The shifts f - q (f in the footprint, q in the cell) fill a rectangle; the cell is listed when the wedge's arc
    of radius x may meet it (its least length within the wedge <= x <= its farthest corner): a superset, so
    the deepest inner top over the list is never shallower than the one over the cells really touched (safe)."""
    g = dist.BOX_GROW
    n = ring_count(reach)
    rx, ry = math.ceil(reach) + 3, math.ceil(reach / sy) + 3
    oy, ox = (a.ravel() for a in np.mgrid[-ry:ry + 1, -rx:rx + 1])
    x0, x1 = -ox - 1.5 - g, -ox + 0.5 + g
    y0, y1 = -(oy + 1.5) * sy - g, -(oy - 0.5) * sy + g
    near = wedge_rho(x0, x1, y0, y1, b)
    far = np.hypot(np.maximum(np.abs(x0), np.abs(x1)), np.maximum(np.abs(y0), np.abs(y1)))
    out = []
    for step in range(1, n + 1):
        x = step * HORIZON_STEP
        on = (near <= x + 1e-9) & (far >= x - 1e-9)
        out.append((ox[on], oy[on]))
    return out


#: cot(ANGLE_SLACK): widening a polar angle arccot(g) by the slack gives cot = (g COT_SLACK - 1) / (g + COT_SLACK).
COT_SLACK = 1.0 / math.tan(ANGLE_SLACK)


def widened_cot(g):
    """cot(arccot(g) + ANGLE_SLACK) for g > 0, else 0 (no cut): the visibility cut widened as the bins are."""
    g = np.asarray(g, np.float64)
    return np.maximum((g * COT_SLACK - 1.0) / (g + COT_SLACK), 0.0)


def horizon(depth: np.ndarray, slices: int, height_scale: float, sectors: int, max_angle: float,
            reach: float, at: tuple | None = None) -> np.ndarray:
    """The visibility cut per sector and voxel, float64 (sectors, Dz, H, W): the cot of the largest polar angle of
    a ray of the sector that can reach the voxel box unblocked (widened by ANGLE_SLACK), 0 where nothing is cut.
    g = max over x of (top of the box - the deepest inner top over the x ring) / x (module docstring). ``at``:
    (slice, row, column) index arrays: the cut at those voxels only, (sectors, N)."""
    h, w = depth.shape
    sw = height_scale * w
    tops = inner_tops(depth) * sw
    box_tops = np.arange(slices, dtype=np.float64) * (sw / slices) - dist.BOX_GROW
    if at is None:
        rows, cols = np.arange(h), np.arange(w)
        above, shape = box_tops[:, None, None], (slices, h, w)
    else:
        kk, jj, ii = at
        above, shape = box_tops[kk], np.shape(kk)
    out = np.zeros((sectors, *shape))
    for s, b in enumerate(bins(sectors, 1, max_angle)):
        g = np.zeros(out.shape[1:])
        for n, (ox, oy) in enumerate(horizon_rings(b, w / h, reach), start=1):
            if not ox.size:
                continue
            if at is None:  # the whole map: one shifted copy of the tops per offset
                m = np.full((h, w), -np.inf)
                for dx, dy in zip(ox, oy):
                    np.maximum(m, tops[(rows + dy) % h][:, (cols + dx) % w], out=m)
            else:
                m = tops[(jj[:, None] + oy) % h, (ii[:, None] + ox) % w].max(axis=1)
            np.maximum(g, (above - m) / (n * HORIZON_STEP), out=g)
        out[s] = widened_cot(g)
    return out
