"""Donnelly's regime (GPU Gems 2, ch. 8), the one the refined-distance paper claims "fewer iterations without loss
of accuracy" in: a fixed number of sphere-tracing steps, each one TRILINEAR lookup of the distance volume, and the
point reached after the last step taken as the hit; no finish (no exact cell solve, no secant step). A float64
numpy model of that loop on this project's maps (the refined kind picks its volume by the ray's direction bin, as
the product's tracer does), measured against the float64 exact first hit (``relief.reference.exact_hit``).

The maps are conservative for a NEAREST lookup anywhere in a voxel; a trilinear lookup blends neighbours whose
values may exceed the distance at the lookup point, so a step can pass the surface: the model reports such rays
(``passed``: the point reached lies past the exact hit along the ray by more than PASS_TOLERANCE).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from maptools.kinds.distance_refined.bins import volume_index

#: A point reached past the exact hit by more than this along the ray (texels) has gone through the surface.
PASS_TOLERANCE = 0.5


@dataclass
class Marched:
    t: np.ndarray  # (N,) layer depth reached after the last step
    uv: np.ndarray  # (N, 2) the point reached


def trilinear(volume: np.ndarray, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Trilinear lookup of ``volume`` (Dz, H, W) at texel-centre coordinates (x, y, z) (texel i's centre at i):
    repeat in x and y, clamp to the edge in z, as a sampler with repeat/repeat/clamp addressing."""
    dz, h, w = volume.shape
    z = np.clip(z, 0.0, dz - 1.0)
    x0, y0, z0 = np.floor(x), np.floor(y), np.minimum(np.floor(z), max(dz - 2, 0))
    fx, fy, fz = x - x0, y - y0, z - z0
    xi = [np.mod(x0, w).astype(np.int64), np.mod(x0 + 1, w).astype(np.int64)]
    yi = [np.mod(y0, h).astype(np.int64), np.mod(y0 + 1, h).astype(np.int64)]
    zi = [z0.astype(np.int64), np.minimum(z0 + 1, dz - 1).astype(np.int64)]
    out = np.zeros_like(x, dtype=np.float64)
    for a, wz in ((0, 1 - fz), (1, fz)):
        for b, wy in ((0, 1 - fy), (1, fy)):
            for c, wx in ((0, 1 - fx), (1, fx)):
                out += wz * wy * wx * volume[zi[a], yi[b], xi[c]]
    return out


def march(volumes: np.ndarray, uv0, view_dir, height_scale: float, iterations: int, *, sectors: int = 1,
          bands: int = 1, max_angle: float | None = None) -> Marched:
    """Donnelly's loop: ``iterations`` steps t += distance(p) / |dp/dt| from the surface plane (t = 0), each a
    trilinear lookup of ``volumes`` ((Dz, H, W) plain, or the refined kind's (V, Dz, H, W) with its bins); stored
    distances are in texels of u, as the maps store them."""
    vol = np.asarray(volumes, np.float64)
    vol = vol[None] if vol.ndim == 3 else vol
    _, slices, rows, cols = vol.shape
    uv0 = np.asarray(uv0, np.float64)
    v = np.asarray(view_dir, np.float64)
    which = np.zeros(len(uv0), np.int64) if max_angle is None else volume_index(v, sectors, bands, max_angle)
    span = v[:, :2] / v[:, 2:3] * height_scale
    per_t = cols * np.sqrt((span ** 2).sum(axis=1) + height_scale ** 2)
    t = np.zeros(len(uv0))
    groups = [(k, np.flatnonzero(which == k)) for k in np.unique(which)]
    for _ in range(iterations):
        at = uv0 - span * t[:, None]
        radius = np.empty_like(t)
        for k, idx in groups:
            radius[idx] = trilinear(vol[k], at[idx, 0] * cols - 0.5, at[idx, 1] * rows - 0.5, t[idx] * slices - 0.5)
        t = np.minimum(t + radius / per_t, 1.0)
    return Marched(t, uv0 - span * t[:, None])


@dataclass
class Accuracy:
    p95: float  # texels: 95th percentile of |uv reached - uv of the exact hit| x map size
    max: float
    passed: float  # fraction of the rays whose point lies past the exact hit (through the surface)
    rays: int


def accuracy(marched: Marched, exact_t: np.ndarray, exact_uv: np.ndarray, size: tuple[int, int], view_dir,
             height_scale: float) -> Accuracy:
    """Error of ``marched`` against the exact hits of the rays ``view_dir`` (rays without one left out), texels of
    u and v (``size`` = (W, H))."""
    ok = np.isfinite(exact_t)
    d = (marched.uv[ok] - exact_uv[ok]) * np.asarray(size, np.float64)
    err = np.hypot(d[:, 0], d[:, 1])
    v = np.asarray(view_dir, np.float64)[ok]
    span = v[:, :2] / v[:, 2:3] * height_scale
    per_t = size[0] * np.sqrt((span ** 2).sum(axis=1) + height_scale ** 2)  # texels along the ray per unit t
    passed = (marched.t[ok] - exact_t[ok]) * per_t > PASS_TOLERANCE
    if not err.size:
        return Accuracy(float("nan"), float("nan"), 0.0, 0)
    return Accuracy(float(np.percentile(err, 95)), float(err.max()), float(passed.mean()), int(err.size))
