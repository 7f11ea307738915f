"""The plain distance map of maptools version 2 (before the box-exact map), kept here only as the baseline the study
measures the other maps against: per voxel the exact distance from the voxel *centre*
to the cell-min solid S' (each bilinear cell x [least corner depth, inf)), minus half the voxel diagonal and the
0.001 store margin. Never larger than the box-exact value on the same solid (dist(box, S') >= dist(centre, S') - h;
tests/lab/studies checks it), so it is as safe, and looser.
"""

from __future__ import annotations

import numpy as np

from maptools.volume.cpu import STORE_MARGIN, round_down


def _gdt_axis(f: np.ndarray, step: float) -> np.ndarray:
    """out[..., i] = min over periodic offsets o of f[..., i + o] + (o step)^2 along the last axis (exact: offsets
    walked outwards, stopped once the gap alone reaches every current value)."""
    out = f.copy()
    for o in range(1, f.shape[-1] // 2 + 1):
        g2 = (o * step) ** 2
        if g2 >= out.max():
            break
        np.minimum(out, np.roll(f, o, axis=-1) + g2, out=out)
        np.minimum(out, np.roll(f, -o, axis=-1) + g2, out=out)
    return out


def plain_before(height: np.ndarray, *, slices: int, height_scale: float) -> np.ndarray:
    """float32 (Dz, H, W) as maptools-2 built it: max(0, d(centre, S') - h - 0.001), rounded down."""
    depth = 1.0 - np.asarray(height, np.float64)
    h, w = depth.shape
    sw, sy = height_scale * w, w / h
    # From above a texel centre the nearest point of a cell box is above one of its corners q, whose least
    # surrounding cell floor is the minimum over the 3x3 texels around q.
    floor = np.min([np.roll(depth, (dy, dx), axis=(0, 1)) for dy in (-1, 0, 1) for dx in (-1, 0, 1)], axis=0) * sw
    half_diagonal = 0.5 * np.sqrt(1.0 + sy ** 2 + (sw / slices) ** 2)
    out = np.empty((slices, h, w))
    for k in range(slices):
        centre = (k + 0.5) / slices * sw
        f = np.maximum(floor - centre, 0.0) ** 2
        f = _gdt_axis(f, 1.0)
        f = _gdt_axis(f.T, sy).T
        out[k] = np.sqrt(f)
    return round_down(np.maximum(out - half_diagonal - STORE_MARGIN, 0.0), np.float32)
