"""Tiny float64 CPU tracers through the generated maps (for tests and measurements, not for rendering).

``sphere_trace`` follows docs/maps.md ("Tracing with a distance map") exactly: nearest-voxel lookups, step by
the stored value along the unit ray in the texel metric, stop when the value is below ``stop`` (or t >= 1 or
after ``max_steps``). Vectorised over rays.
"""

from __future__ import annotations

import numpy as np


def sphere_trace(vol: np.ndarray, uv0, view_dir, height_scale: float, *, stop: float = 1e-3,
                 max_steps: int = 256) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Trace rays entering at ``uv0`` (N, 2) with tangent-space view vectors ``view_dir`` (N, 3), V.z > 0, through
    the distance volume ``vol`` (Dz, H, W). Returns (t at the stop point, steps taken, capped flag)."""
    dz, h, w = vol.shape
    uv0 = np.atleast_2d(np.asarray(uv0, np.float64))
    v = np.atleast_2d(np.asarray(view_dir, np.float64))
    n = max(len(uv0), len(v))
    uv0, v = np.broadcast_to(uv0, (n, 2)), np.broadcast_to(v, (n, 3))
    if not (v[:, 2] > 0).all():
        raise ValueError("sphere_trace needs V.z > 0 for every ray")
    sw = height_scale * w
    norm = np.linalg.norm(v, axis=1)
    wx, wy, wz = -v[:, 0] / norm, -v[:, 1] / norm, v[:, 2] / norm  # unit direction, metric space, Z down
    x, y, z = uv0[:, 0] * w, uv0[:, 1] * w, np.zeros(n)
    steps = np.zeros(n, np.int64)
    done = np.zeros(n, bool)
    flat = np.asarray(vol, np.float64).ravel()
    for _ in range(max_steps):
        run = np.flatnonzero(~done)
        if not run.size:
            break
        t = z[run] / sw
        i = np.mod(np.floor(x[run]), w).astype(np.int64)
        j = np.mod(np.floor(y[run] * h / w), h).astype(np.int64)
        k = np.clip(np.floor(t * dz), 0, dz - 1).astype(np.int64)
        m = flat[(k * h + j) * w + i]
        steps[run] += 1
        fin = (m < stop) | (t >= 1.0)
        done[run[fin]] = True
        go = run[~fin]
        mg = m[~fin]
        x[go] += mg * wx[go]
        y[go] += mg * wy[go]
        z[go] += mg * wz[go]
    return z / sw, steps, ~done
