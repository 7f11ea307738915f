"""CPU reference for the 3D distance maps (Donnelly) and the visibility-refined distance map (seed 000).

Metric ("texel metric", see docs/maps.md). A W x H height map with height_scale S and Dz slices spans the
periodic box [0, W) x [0, W) x [0, S*W] of metric space: X = u*W, Y = v*W, Z = t*S*W (t = layer depth).
One unit = one texel along u; v is scaled by the aspect W/H (the tangent frame is isotropic in UV units), depth
by S*W. Voxel (i, j, k) has its centre at X = i + 0.5, Y = (j + 0.5) * W/H, Z = (k + 0.5) * S*W/Dz, i.e. above
the texel centres, and its box is [i, i+1] x [j, j+1]*W/H x [k, k+1]*S*W/Dz.

Surface used for the distances: S' = the union over the bilinear cells (between four texel centres) of the
half-infinite boxes  cell x [min of the four corner depths, inf).  The bilinear solid {t >= D(u, v)} lies inside
S' (a bilinear patch never goes above its highest corner), so distances to S' are lower bounds of distances to
the relief: the plain map is exact for S' and conservative for the real surface.
For a voxel centre (always above a texel centre) the nearest point of a cell box lies on the column above one of
the cell's corners, so the distance to S' is

    d(i, j, k)^2 = min over texels q of  wrapdx^2 + (W/H)^2 wrapdy^2 + ((E_q - t_k)^+ * S*W)^2,
    E_q = min of D over the 3x3 texels around q (the cells that touch q),

a separable generalised distance transform computed here exactly (float64, brute force over offsets with an
exact early exit). The stored value subtracts the half voxel diagonal h (so that a NEAREST lookup anywhere inside
the voxel's box, or a trilinear lookup, stays a lower bound: the distance is 1-Lipschitz) and a float-rounding
margin, and clamps at 0.
"""

from __future__ import annotations

import math

import numpy as np

from wgpuviewer.core.errors import UserError

#: Largest volume (W * H * slices) the 3D kinds generate: 2^23 voxels = 32 MiB of float32 (e.g. 512x512x32).
MAX_VOXELS = 1 << 23
#: Subtracted from every stored distance (texels): covers float32 rounding of the result and of the GPU arithmetic.
STORE_MARGIN = 1e-3


# -- geometry ---------------------------------------------------------------------------------------

def spacing(w: int, h: int, slices: int, height_scale: float) -> tuple[float, float, float]:
    """Voxel spacing (sx, sy, sz) in texel-metric units: 1, W/H, S*W/Dz."""
    return 1.0, w / h, height_scale * w / slices


def half_diagonal(w: int, h: int, slices: int, height_scale: float) -> float:
    """Largest distance from a voxel centre to a point of its box (= half the voxel diagonal)."""
    sx, sy, sz = spacing(w, h, slices, height_scale)
    return 0.5 * math.sqrt(sx * sx + sy * sy + sz * sz)


def check_volume(w: int, h: int, slices: int, kind: str = "distance") -> None:
    n = w * h * slices
    if n > MAX_VOXELS:
        raise UserError(f"{kind}: a {w}x{h}x{slices} volume has {n} voxels, more than the limit {MAX_VOXELS} "
                        f"({MAX_VOXELS * 4 >> 20} MiB of float32); downscale the height map or use fewer --slices")


def neighbourhood(depth: np.ndarray, op) -> np.ndarray:
    """op (np.minimum / np.maximum) over the 3x3 texels around each texel, with wrap (repeat) addressing."""
    out = depth.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            if dx or dy:
                op(out, np.roll(depth, (dy, dx), axis=(0, 1)), out=out)
    return out


def layer_depths(slices: int) -> np.ndarray:
    """t at the voxel centres: (k + 0.5) / Dz."""
    return (np.arange(slices, dtype=np.float64) + 0.5) / slices


def _gdt_axis(f: np.ndarray, axis: int, weight2: float) -> np.ndarray:
    """out[i] = min over q of (periodic |q - i|)^2 * weight2 + f[q] along ``axis``; exact."""
    n = f.shape[axis]
    out = f.copy()
    for a in range(1, n // 2 + 1):
        c = a * a * weight2
        if c >= out.max():  # no candidate at this or a larger offset can beat any current value
            break
        cand = np.minimum(np.roll(f, a, axis=axis), np.roll(f, -a, axis=axis))
        cand += c
        np.minimum(out, cand, out=out)
    return out


def column_edt(tops: np.ndarray, slices: int, height_scale: float, solid_below: bool = True) -> np.ndarray:
    """Exact distance (float64, (Dz, H, W)) from every voxel centre to the union of vertical columns at the texel
    centres: column q occupies t >= tops[q] (solid_below) or t <= tops[q] (free space), unbounded in t."""
    h, w = tops.shape
    t = layer_depths(slices)[:, None, None]
    gap = (tops[None] - t) if solid_below else (t - tops[None])
    f = (np.maximum(gap, 0.0) * (height_scale * w)) ** 2
    f = _gdt_axis(f, 2, 1.0)
    f = _gdt_axis(f, 1, (w / h) ** 2)
    return np.sqrt(f)


def solid_distance(depth: np.ndarray, slices: int, height_scale: float) -> np.ndarray:
    """Exact distance from each voxel centre to S' (the cell-min superset of the bilinear solid)."""
    return column_edt(neighbourhood(depth, np.minimum), slices, height_scale, True)


def free_distance(depth: np.ndarray, slices: int, height_scale: float) -> np.ndarray:
    """Exact distance from each voxel centre to F' = cells x (-inf, max corner depth]: a superset of the free
    space {t < D} above the bilinear surface, so this is a lower bound of the depth inside the relief."""
    return column_edt(neighbourhood(depth, np.maximum), slices, height_scale, False)


def store(d: np.ndarray, w: int, h: int, slices: int, height_scale: float) -> np.ndarray:
    """Stored (safe) value: max(0, d - half voxel diagonal - STORE_MARGIN), float32."""
    hd = half_diagonal(w, h, slices, height_scale)
    return np.maximum(d - (hd + STORE_MARGIN), 0.0).astype(np.float32)


def distance(height: np.ndarray, *, slices: int = 16, height_scale: float = 0.05) -> np.ndarray:
    """Distance volume, float32 (Dz, H, W): safe sphere-tracing radius per voxel in texel-metric units."""
    hh, w = height.shape
    check_volume(w, hh, slices)
    depth = 1.0 - height.astype(np.float64)
    return store(solid_distance(depth, slices, height_scale), w, hh, slices, height_scale)


# -- refined map ------------------------------------------------------------------------------------

#: Forward (free path) march: at most this many sphere steps per voxel and direction.
REFINE_FORWARD_STEPS = 48
#: Backward (visibility) test: at most this many samples per voxel and direction.
REFINE_BACKWARD_SAMPLES = 24


def cone_directions(max_angle: float, angle_step: float) -> tuple[np.ndarray, float]:
    """Unit directions (N, 3) covering the cone of half-angle ``max_angle`` (degrees) around +Z (downwards into
    the relief), and alpha (radians): every direction of the cone is within alpha of one of them.

    Rings at theta_i = i * delta (i = 0..n, delta = max_angle / n <= angle_step), ring i with
    m_i = ceil(2 pi sin theta_i / delta) azimuths. A direction at (theta, phi) is within delta/2 (along the
    meridian) of the nearest ring and within sin(theta_r) * pi / m_r <= delta/2 (along that ring) of a sample, so
    by the triangle inequality alpha = delta.
    """
    n = max(1, math.ceil(max_angle / angle_step - 1e-9))
    delta = math.radians(max_angle) / n
    dirs = []
    for i in range(n + 1):
        th = i * delta
        m = 1 if i == 0 else max(1, math.ceil(2 * math.pi * math.sin(th) / delta))
        for j in range(m):
            ph = 2 * math.pi * (j + 0.5 * (i % 2)) / m
            dirs.append((math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)))
    return np.array(dirs, np.float64), delta


class _Field:
    """Nearest-voxel lower bound of a 1-Lipschitz distance given at voxel centres (float64 CPU twin of the WGSL)."""

    def __init__(self, vol: np.ndarray, sp: tuple[float, float, float]):
        self.flat = vol.ravel()
        self.dz, self.h, self.w = vol.shape
        self.sp = sp

    def lower(self, x, y, z):
        sx, sy, sz = self.sp
        fi, fj = np.floor(x / sx), np.floor(y / sy)
        fk = np.clip(np.floor(z / sz), 0, self.dz - 1)
        off = np.sqrt((x - (fi + 0.5) * sx) ** 2 + (y - (fj + 0.5) * sy) ** 2 + (z - (fk + 0.5) * sz) ** 2)
        i = np.mod(fi, self.w).astype(np.int64)
        j = np.mod(fj, self.h).astype(np.int64)
        idx = (fk.astype(np.int64) * self.h + j) * self.w + i
        return self.flat[idx] - off


def refine(dsolid: np.ndarray, dfree: np.ndarray, w: int, h: int, slices: int, height_scale: float,
           max_angle: float, angle_step: float) -> np.ndarray:
    """Refined distances (float64, before `store`'s margin), from the exact S' and F' distance volumes.

    For voxel centre c and sampled direction s (unit, within the cone): eps = half voxel diagonal,
    alpha = covering angle of the direction set. A real ray (p, w) with |p - c| <= eps and angle(w, s) <= alpha
    stays within eps + L*alpha of the sampled ray c + L s after a length L. So
      * free path: l_s = first L with  dS'(c + L s) <= eps + L alpha  (found by safe steps of the (1+alpha)-
        Lipschitz function g(L) = lowerbound_dS'(c + L s) - eps - L alpha, stopped early when g <= 0 or after
        REFINE_FORWARD_STEPS: stopping early only shortens l_s), is <= the real ray's free path;
      * visibility: (c, s) counts as occluded only if a sample c - L s (L > 0, t >= 0) has
        lowerbound_dF'(.) > eps + L alpha, i.e. every nearby real ray certainly passes through the relief.
        Skipping samples only declares more directions admissible (smaller minimum): safe.
    Result (a safe nearest-lookup value, before the rounding margin): max(euclid - eps, min over admissible s of
    l_s); voxels with no admissible direction keep euclid - eps (both terms are lower bounds of the real free path).
    """
    dirs, alpha = cone_directions(max_angle, angle_step)
    sp = spacing(w, h, slices, height_scale)
    eps = half_diagonal(w, h, slices, height_scale)
    fs, ff = _Field(dsolid, sp), _Field(dfree, sp)
    zc, yc, xc = np.meshgrid((np.arange(slices) + 0.5) * sp[2], (np.arange(h) + 0.5) * sp[1],
                             (np.arange(w) + 0.5) * sp[0], indexing="ij")
    euclid = dsolid.ravel()
    best = np.full(euclid.shape, np.inf)
    active = np.flatnonzero(euclid > eps)  # elsewhere every l_s = 0: the stored value is 0 either way
    x0, y0, z0 = xc.ravel()[active], yc.ravel()[active], zc.ravel()[active]
    bstep_min = 0.5 * min(sp)
    for s in dirs:
        b = best[active]
        # forward: free path along s
        L = np.zeros(active.size)
        run = np.ones(active.size, bool)
        for _ in range(REFINE_FORWARD_STEPS):
            idx = np.flatnonzero(run)
            if not idx.size:
                break
            Li = L[idx]
            g = fs.lower(x0[idx] + Li * s[0], y0[idx] + Li * s[1], z0[idx] + Li * s[2]) - eps - Li * alpha
            stop = (g <= 0) | (Li >= b[idx])
            run[idx[stop]] = False
            go = idx[~stop]
            L[go] += g[~stop] / (1.0 + alpha)
        cand = np.flatnonzero(b > L)
        if not cand.size:
            continue
        # backward: is (c, s) certainly occluded?
        lend = z0[cand] / s[2]  # length back to the top plane t = 0
        bstep = np.maximum(lend / REFINE_BACKWARD_SAMPLES, bstep_min)
        occluded = np.zeros(cand.size, bool)
        for q in range(1, REFINE_BACKWARD_SAMPLES + 1):
            Lb = q * bstep
            ok = (Lb <= lend) & ~occluded
            if not ok.any():
                break
            k = cand[ok]
            Lk = Lb[ok]
            inside = ff.lower(x0[k] - Lk * s[0], y0[k] - Lk * s[1], z0[k] - Lk * s[2]) > eps + Lk * alpha
            occluded[np.flatnonzero(ok)[inside]] = True
        keep = cand[~occluded]
        best[active[keep]] = np.minimum(best[active[keep]], L[keep])
    out = np.where(np.isfinite(best), np.maximum(euclid - eps, best), euclid - eps)
    return out.reshape(dsolid.shape)


def distance_refined(height: np.ndarray, *, slices: int = 16, height_scale: float = 0.05, max_angle: float = 80.0,
                     angle_step: float = 6.0) -> np.ndarray:
    """Visibility-refined distance volume, float32 (Dz, H, W), same metric and lookup rule as `distance`."""
    hh, w = height.shape
    check_volume(w, hh, slices, "distance_refined")
    depth = 1.0 - height.astype(np.float64)
    ds = solid_distance(depth, slices, height_scale)
    df = free_distance(depth, slices, height_scale)
    r = refine(ds, df, w, hh, slices, height_scale, max_angle, angle_step)
    return np.maximum(r - STORE_MARGIN, 0.0).astype(np.float32)
