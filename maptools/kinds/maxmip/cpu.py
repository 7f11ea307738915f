"""The maxmip kind's CPU reference: the maximum pyramid (numpy), and its level sizes (the renderer's atlases use them)."""

from __future__ import annotations

import numpy as np


def level_sizes(h: int, w: int) -> list[tuple[int, int]]:
    """(rows, cols) of every pyramid level: ceil halving down to 1x1."""
    sizes = [(h, w)]
    while sizes[-1] != (1, 1):
        hh, ww = sizes[-1]
        sizes.append(((hh + 1) // 2, (ww + 1) // 2))
    return sizes


def covered_range(i: int, n: int, p: int) -> tuple[int, int]:
    """Children [lo, hi] (inclusive) of parent i when n children reduce to p = ceil(n/2) parents."""
    return (i * n) // p, min(2 * i + 1, n - 1)


def _reduce_axis0(a: np.ndarray, p: int) -> np.ndarray:
    n = a.shape[0]
    out = np.empty((p,) + a.shape[1:], a.dtype)
    # Regular part: parents whose range is exactly 2i..2i+1; the rest (odd sizes) one by one.
    for i in range(p):
        lo, hi = covered_range(i, n, p)
        out[i] = a[lo:hi + 1].max(axis=0)
    return out


def maxmip(height: np.ndarray) -> list[np.ndarray]:
    """Maximum pyramid: list of float32 arrays, level 0 = the input, last = 1x1 (the global max).

    Parent i covers children floor(i*n/p) .. min(2i+1, n-1) per axis (p = ceil(n/2)), a superset of the
    index-space children 2i..2i+1 and of the children its UV span overlaps: conservative for odd sizes.
    """
    levels = [np.ascontiguousarray(height, dtype=np.float32)]
    for ph, pw in level_sizes(*height.shape)[1:]:
        a = levels[-1]
        if a.shape[0] % 2 == 0 and a.shape[1] % 2 == 0:
            b = a.reshape(ph, 2, pw, 2).max(axis=(1, 3))
        else:
            b = _reduce_axis0(_reduce_axis0(a, ph).T, pw).T
        levels.append(np.ascontiguousarray(b, dtype=np.float32))
    return levels
