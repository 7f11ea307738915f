"""Tiny float64 CPU tracers through the generated maps (for tests and measurements, not for rendering).

``sphere_trace`` follows docs/maps.md ("Tracing with a distance map") exactly: nearest-voxel lookups, step by
the stored value along the unit ray in the texel metric, stop when the value is below ``stop`` (or t >= 1 or
after ``max_steps``). Vectorised over rays.
"""

from __future__ import annotations

import numpy as np

from wgpuviewer.core.sampling import bilinear


def _rays(uv0, view_dir, who: str) -> tuple[np.ndarray, np.ndarray, int]:
    """Entry points (N, 2) and view vectors (N, 3) as float64, broadcast against each other; V.z > 0 required."""
    uv0 = np.atleast_2d(np.asarray(uv0, np.float64))
    v = np.atleast_2d(np.asarray(view_dir, np.float64))
    n = max(len(uv0), len(v))
    uv0, v = np.broadcast_to(uv0, (n, 2)), np.broadcast_to(v, (n, 3))
    if not (v[:, 2] > 0).all():
        raise ValueError(f"{who} needs V.z > 0 for every ray")
    return uv0, v, n


def sphere_trace(vol: np.ndarray, uv0, view_dir, height_scale: float, *, stop: float = 1e-3,
                 max_steps: int = 256, which=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Trace rays entering at ``uv0`` (N, 2) with tangent-space view vectors ``view_dir`` (N, 3), V.z > 0, through
    the distance volume ``vol`` (Dz, H, W), or through volume ``which[n]`` of a (V, Dz, H, W) stack (the refined
    kind; ``maptools.kinds.distance_refined.bins.volume_index`` picks a ray's volume). Returns (t at the stop point, steps taken,
    capped flag)."""
    vol = np.asarray(vol, np.float64)
    vol = vol[None] if vol.ndim == 3 else vol
    _, dz, h, w = vol.shape
    uv0, v, n = _rays(uv0, view_dir, "sphere_trace")
    which = np.zeros(n, np.int64) if which is None else np.broadcast_to(np.asarray(which, np.int64), (n,))
    sw = height_scale * w
    norm = np.linalg.norm(v, axis=1)
    wx, wy, wz = -v[:, 0] / norm, -v[:, 1] / norm, v[:, 2] / norm  # unit direction, metric space, Z down
    x, y, z = uv0[:, 0] * w, uv0[:, 1] * w, np.zeros(n)
    steps = np.zeros(n, np.int64)
    done = np.zeros(n, bool)
    flat = vol.ravel()
    for _ in range(max_steps):
        run = np.flatnonzero(~done)
        if not run.size:
            break
        t = z[run] / sw
        i = np.mod(np.floor(x[run]), w).astype(np.int64)
        j = np.mod(np.floor(y[run] * h / w), h).astype(np.int64)
        k = np.clip(np.floor(t * dz), 0, dz - 1).astype(np.int64)
        m = flat[((which[run] * dz + k) * h + j) * w + i]
        steps[run] += 1
        fin = (m < stop) | (t >= 1.0)
        done[run[fin]] = True
        go = run[~fin]
        mg = m[~fin]
        x[go] += mg * wx[go]
        y[go] += mg * wy[go]
        z[go] += mg * wz[go]
    return z / sw, steps, ~done


#: cone_trace outcomes
BRACKETED, GAP_STOP, CAPPED = 0, 1, 2


def _lookup_nearest(cmap: np.ndarray, x, y):
    h, w = cmap.shape
    i = np.mod(np.floor(x), w).astype(np.int64)
    j = np.mod(np.floor(y * h / w), h).astype(np.int64)
    return cmap.ravel()[j * w + i].astype(np.float64)


def _lookup_bilinear(cmap: np.ndarray, x, y):
    """Bilinear between texel centres, repeat addressing (the GPU sampler's filter, ideal weights)."""
    h, w = cmap.shape
    fx, fy = x - 0.5, y * h / w - 0.5
    cx, cy = np.floor(fx), np.floor(fy)
    ax, ay = fx - cx, fy - cy
    flat = np.asarray(cmap, np.float64).ravel()
    i0, i1 = np.mod(cx, w).astype(np.int64), np.mod(cx + 1, w).astype(np.int64)
    j0, j1 = np.mod(cy, h).astype(np.int64) * w, np.mod(cy + 1, h).astype(np.int64) * w
    return ((flat[j0 + i0] * (1 - ax) + flat[j0 + i1] * ax) * (1 - ay)
            + (flat[j1 + i0] * (1 - ax) + flat[j1 + i1] * ax) * ay)


def cone_trace(cmap: np.ndarray, depth: np.ndarray, uv0, view_dir, height_scale: float, *, lookup: str = "nearest",
               max_steps: int = 256, gap_stop: float = 1e-5, bisect: int = 16):
    """Relaxed cone stepping (docs/maps.md, "Relaxed cone map"), float64, vectorised over rays.

    ``cmap`` (H, W): cone ratios (texels of u per unit t); ``depth`` (H, W): D = 1 - H, sampled bilinear with
    repeat addressing (``wgpuviewer.core.sampling.bilinear``). Per ray, from t = 0 at uv0, with
    k = |V.xy / V.z| * S * W (texels travelled per unit t):

        loop (<= max_steps):  D = depth(p) (bilinear);  if t >= D: bracket [t_prev, t]; break
                              if D - t <= gap_stop: stop (GAP_STOP); break
                              c = cone(p) (nearest texel, or bilinear if the map was built with filter=bilinear)
                              dt = (D - t) * (c / (k + c))   (dt = D - t when k == 0)
                              t_prev = t;  t += dt;  uv -= dt * (V.xy / V.z) * S
        then ``bisect`` halvings of [t_prev, t] keeping a free lower and a solid upper end.

    Returns a dict of arrays: t (final: the solid end of the bracket, or the stop point), lo / hi (the cone phase's
    bracket: lo = last free point, hi = first solid point; hi = NaN without a bracket), steps (cone steps = depth
    fetches of the cone phase), status (BRACKETED, GAP_STOP, CAPPED).
    """

    rows, cols = depth.shape
    uv0, v, n = _rays(uv0, view_dir, "cone_trace")
    dxy = -v[:, :2] / v[:, 2:3] * height_scale * cols  # texels of u per unit t
    k = np.hypot(dxy[:, 0], dxy[:, 1])
    p0 = uv0 * cols
    t = np.zeros(n)
    lo = np.zeros(n)
    hi = np.full(n, np.nan)
    steps = np.zeros(n, np.int64)
    status = np.full(n, CAPPED)
    run = np.arange(n)

    def depth_at(idx, tt):
        p = p0[idx] + tt[:, None] * dxy[idx]
        return bilinear(depth, p / cols), p

    for _ in range(max_steps):
        if not run.size:
            break
        d, p = depth_at(run, t[run])
        steps[run] += 1
        solid = t[run] >= d
        hi[run[solid]] = t[run[solid]]
        status[run[solid]] = BRACKETED
        gap = (~solid) & (d - t[run] <= gap_stop)
        status[run[gap]] = GAP_STOP
        go = ~(solid | gap)
        idx, d, p = run[go], d[go], p[go]
        c = _lookup_nearest(cmap, p[:, 0], p[:, 1]) if lookup == "nearest" else _lookup_bilinear(cmap, p[:, 0], p[:, 1])
        kk = k[idx]
        frac = np.where(kk > 0, c / np.where(kk + c > 0, kk + c, 1.0), 1.0)
        lo[idx] = t[idx]
        t[idx] = t[idx] + (d - t[idx]) * frac
        run = idx
    # binary search inside the brackets: lo free, hi solid
    b = np.flatnonzero(status == BRACKETED)
    a_lo, a_hi = lo[b].copy(), hi[b].copy()
    for _ in range(bisect):
        mid = 0.5 * (a_lo + a_hi)
        d, _ = depth_at(b, mid)
        s = mid >= d
        a_hi = np.where(s, mid, a_hi)
        a_lo = np.where(s, a_lo, mid)
    t[b] = a_hi
    return {"t": t, "lo": lo, "hi": hi, "steps": steps, "status": status, "bisect_lo": _put(n, b, a_lo)}


def _put(n, idx, vals):
    out = np.full(n, np.nan)
    out[idx] = vals
    return out
