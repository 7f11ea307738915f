"""float64 twins of WGSL searches that tests compare the GPU against (beyond wgpuviewer.relief.reference's exact hit)."""

from __future__ import annotations

import numpy as np

from wgpuviewer.core.sampling import bilinear


def pom_from(height, uv0, view, height_scale, t0, n, depth_range):
    """float64 POM over [max(t0, lo), hi] (n layers, bilinear repeat sampling; (lo, hi): the map's depth range):
    pom_search's arithmetic."""
    span = view[:, :2] / view[:, 2:3] * height_scale
    depth = 1.0 - height
    t0 = np.clip(np.maximum(t0, depth_range[0]), 0.0, 1.0)
    step = (np.maximum(depth_range[1], t0) - t0) / n
    t_hit = np.full(len(uv0), np.nan)
    prev = None
    for i in range(n + 1):
        t = t0 + i * step
        d = bilinear(depth, uv0 - span * t[:, None])
        if prev is None:
            first = t >= d
            t_hit[first] = t0[first]
        else:
            new = np.isnan(t_hit) & (t >= d)
            after, before = d - t, prev - (t - step)
            w = np.clip(after / np.where(after - before < -1e-12, after - before, -1.0), 0.0, 1.0)
            t_hit[new] = (t - w * step)[new]
        prev = d
    return t_hit
