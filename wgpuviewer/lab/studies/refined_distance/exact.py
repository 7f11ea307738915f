"""The exact-visibility refined map, built by brute force: the bound the paper's idea can reach at best, against which
the product's conservative visibility cut (maptools/kinds/distance_refined/visibility.py) is measured.

The paper's value at a point P: the least free path from P over the directions whose ray reaches P unblocked from the
top. A ray that reaches P unblocked is a ray from the top plane whose first hit lies past P, so the map is made from
such rays alone: per direction bin, random rays (random entry on the top plane, direction uniform in the bin's solid
angle) are cast against the float64 bilinear surface (the exact first hit, a compiled twin of
``wgpuviewer/relief/reference.py``'s cell walk, tested equal to it), and each ray walks the voxels it crosses before
its hit: a voxel box B gets min(value, free path from where the ray leaves B to the hit) (the least over the ray's
points in B). Over many rays per bin this is the least free path over the sampled visible rays that cross B.

The sampling makes it an estimate from ABOVE of the exact value (a ray between the sampled ones may cross B with a
shorter free path): so it bounds what the idea can save, it is no map to ship. ``check`` measures how far above:
fresh random rays of the bin, per ray the largest excess of a stored value over the ray's own free path at a voxel
it crosses. Every value is floored at the product's map of the same bins with the conservative cut (a safe lower
bound of the exact value), which is all that voxels no sampled ray reaches get. Values are rounded down to float16,
as the product stores its maps.

Needs numba (``wgpuviewer[bench]``). May import ``core``, maptools and the study's own modules.
"""

from __future__ import annotations

import math

import numpy as np

from maptools.kinds.distance_refined.bins import Bin, bins
from maptools.volume.cpu import round_down
from wgpuviewer.core.errors import UserError

#: Roots a hair outside a cell's t-interval are rounding, not misses (reference.py's _ROOT_SLACK).
ROOT_SLACK = 1e-12


def _numba():
    try:
        import numba
    except ImportError:
        raise UserError("the refined-distance study's exact-visibility map needs numba: "
                        "pip install 'wgpuviewer[bench]'") from None
    return numba


_KERNELS = {}


def _cell_root(njit):
    """reference.py's cell_root for one ray, compiled."""

    @njit
    def first_root(a, b, c, length):
        disc = b * b - 4.0 * a * c
        if not disc >= 0.0:
            return np.nan
        q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
        best = np.inf
        for r in (q / a, c / q):
            if r >= -ROOT_SLACK and r <= length + ROOT_SLACK and r < best:
                best = r
        if best == np.inf:
            return np.nan
        return min(max(best, 0.0), length)

    @njit
    def cell_root(depth, cx, cy, x0, y0, ax, ay, t_enter, t_exit):
        rows, cols = depth.shape
        i0, i1, j0, j1 = cx % cols, (cx + 1) % cols, cy % rows, (cy + 1) % rows
        c00, c10, c01, c11 = depth[j0, i0], depth[j0, i1], depth[j1, i0], depth[j1, i1]
        b_x, c_y = c10 - c00, c01 - c00
        e_xy = c11 - c10 - c01 + c00
        ex = min(max(x0 + t_enter * ax - cx, 0.0), 1.0)
        ey = min(max(y0 + t_enter * ay - cy, 0.0), 1.0)
        qc = t_enter - (c00 + b_x * ex + c_y * ey + e_xy * ex * ey)
        qb = 1.0 - (b_x * ax + c_y * ay + e_xy * (ex * ay + ey * ax))
        qa = -e_xy * ax * ay
        s = 0.0 if qc >= 0.0 else first_root(qa, qb, qc, t_exit - t_enter)
        if np.isnan(s) and t_exit >= 1.0:
            return t_exit - t_enter
        return s

    return cell_root


def _kernels():
    """The compiled kernels (compiled once per process)."""
    if _KERNELS:
        return _KERNELS
    njit = _numba().njit(error_model="numpy")  # closures: compiled per process, not cached
    cell_root = _cell_root(njit)

    @njit
    def hit(depth, x0, y0, ax, ay, t_start):
        """Layer depth of the first hit at or after t_start of the ray (x, y)(t) = (x0, y0) + t (ax, ay) in cell
        coordinates (texel centre i at x = i), reference.exact_hit's walk."""
        cx = int(math.floor(x0 + ax * t_start))
        cy = int(math.floor(y0 + ay * t_start))
        sx = 1 if ax > 0 else -1
        sy = 1 if ay > 0 else -1
        t_enter = t_start
        while True:
            tx = (cx + (1 if sx > 0 else 0) - x0) / ax if ax != 0 else np.inf
            ty = (cy + (1 if sy > 0 else 0) - y0) / ay if ay != 0 else np.inf
            t_exit = min(min(tx, ty), 1.0)
            s = cell_root(depth, cx, cy, x0, y0, ax, ay, t_enter, t_exit)
            if not np.isnan(s):
                return t_enter + s
            if tx <= t_exit:
                cx += sx
            if ty <= t_exit:
                cy += sy
            t_enter = t_exit

    @njit
    def hits(depth, x0, y0, ax, ay, t_start):
        out = np.empty(len(x0))
        for r in range(len(x0)):
            out[r] = hit(depth, x0[r], y0[r], ax[r], ay[r], t_start[r])
        return out

    @njit
    def walk(depth, vol, x0, y0, ax, ay, per_t, check):
        """Each ray from the top plane (texel coordinates: texel i spans [i, i + 1)) to its first hit, voxel by
        voxel: check False: vol = min(vol, free path from the voxel's exit to the hit); True: per ray the largest
        vol - that free path (how far the stored values exceed this ray's)."""
        slices, rows, cols = vol.shape
        excess = np.full(len(x0), -np.inf)
        for r in range(len(x0)):
            t_hit = hit(depth, x0[r] - 0.5, y0[r] - 0.5, ax[r], ay[r], 0.0)
            i, j, k = int(math.floor(x0[r])), int(math.floor(y0[r])), 0
            sx = 1 if ax[r] > 0 else -1
            sy = 1 if ay[r] > 0 else -1
            while True:
                tx = (i + (1 if sx > 0 else 0) - x0[r]) / ax[r] if ax[r] != 0 else np.inf
                ty = (j + (1 if sy > 0 else 0) - y0[r]) / ay[r] if ay[r] != 0 else np.inf
                tk = (k + 1) / slices
                t_out = min(min(tx, ty), min(tk, t_hit))
                free = (t_hit - t_out) * per_t[r]
                kk = min(k, slices - 1)
                if check:
                    excess[r] = max(excess[r], vol[kk, j % rows, i % cols] - free)
                elif free < vol[kk, j % rows, i % cols]:
                    vol[kk, j % rows, i % cols] = free
                if t_out >= t_hit:
                    break
                if tx <= t_out:
                    i += sx
                if ty <= t_out:
                    j += sy
                if tk <= t_out:
                    k += 1
        return excess

    _KERNELS.update(hits=hits, walk=walk)
    return _KERNELS


def first_hits(depth: np.ndarray, uv0, view_dir, height_scale: float, t_start=None) -> np.ndarray:
    """Layer depth of each ray's first hit at or after ``t_start`` (default 0): the rays of ``reference.exact_hit``
    (entry uv0 (N, 2) on the top plane, tangent-space V (N, 3), V.z > 0), compiled."""
    d = np.ascontiguousarray(depth, np.float64)
    rows, cols = d.shape
    uv0, v = np.asarray(uv0, np.float64), np.asarray(view_dir, np.float64)
    step = -v[:, :2] / v[:, 2:3] * height_scale * (cols, rows)
    start = uv0 * (cols, rows) - 0.5
    t0 = np.zeros(len(uv0)) if t_start is None else np.broadcast_to(np.asarray(t_start, np.float64), len(uv0))
    return _kernels()["hits"](d, start[:, 0].copy(), start[:, 1].copy(), step[:, 0].copy(), step[:, 1].copy(),
                              np.ascontiguousarray(t0))


def directions(b: Bin, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` tangent-space view vectors V (towards the eye) whose travel direction w = (-V.x, -V.y, V.z) is uniform
    in the bin's solid angle (cos of the polar angle uniform, the azimuth uniform in the sector)."""
    cos = rng.uniform(math.cos(b.polar_hi), math.cos(b.polar_lo), n)
    az = rng.uniform(-math.pi, math.pi, n) if b.full else rng.uniform(b.az_lo, b.az_hi, n)
    sin = np.sqrt(1.0 - cos * cos)
    return np.stack([-sin * np.cos(az), -sin * np.sin(az), cos], axis=1)


def _rays(shape, view_dir, height_scale: float, rng):
    """Random entries of the rays V on the top plane, in texel coordinates: x0, y0, the step per unit layer depth,
    the texels of travel per unit layer depth."""
    rows, cols = shape
    n = len(view_dir)
    span = view_dir[:, :2] / view_dir[:, 2:3] * height_scale
    per_t = cols * np.sqrt((span ** 2).sum(axis=1) + height_scale ** 2)
    return (rng.uniform(0, cols, n), rng.uniform(0, rows, n), -span[:, 0] * cols, -span[:, 1] * rows, per_t)


def raw_bins(height: np.ndarray, slices: int, height_scale: float, sectors: int, bands: int, max_angle: float,
             rays_per_texel: int, seed: int = 0) -> np.ndarray:
    """float64 (sectors x bands, Dz, H, W): per bin the least free path over its sampled visible rays crossing each
    voxel (inf where none crosses it), rays_per_texel x W x H random rays per bin."""
    depth = np.ascontiguousarray(1.0 - np.asarray(height, np.float64))
    walk = _kernels()["walk"]
    rng = np.random.default_rng(seed)
    out = np.full((sectors * bands, slices, *depth.shape), np.inf)
    for n, b in enumerate(bins(sectors, bands, max_angle)):
        v = directions(b, rays_per_texel * depth.size, rng)
        walk(depth, out[n], *_rays(depth.shape, v, height_scale, rng), False)
    return out


def stored(raw: np.ndarray, floor: np.ndarray) -> np.ndarray:
    """The map as the tracer reads it, float64 (V + 1, Dz, H, W): each raw volume rounded down to float16 and floored
    at ``floor``, the product's map of the same bins (V + 1 volumes, the plain one last: rays steeper than the binned
    cone): a safe lower bound of the exact value, so also where no sampled ray came."""
    floor = np.asarray(floor, np.float64)
    values = np.where(np.isfinite(raw), round_down(np.minimum(raw, 6.0e4), np.float16).astype(np.float64), 0.0)
    return np.concatenate([np.maximum(values, floor[:-1]), floor[-1:]])


def single_cone(raw: np.ndarray) -> np.ndarray:
    """The paper's map from the bins' raw volumes: one value per voxel for the whole cone (their least)."""
    return raw.min(axis=0, keepdims=True)


def check(height: np.ndarray, volumes: np.ndarray, height_scale: float, sectors: int, bands: int, max_angle: float,
          rays_per_bin: int, seed: int) -> np.ndarray:
    """Per fresh random visible ray of every bin (``rays_per_bin`` each), the largest excess (texels) of the stored
    value of a voxel it crosses over its own free path from there: > 0 where the map would let that ray pass."""
    depth = np.ascontiguousarray(1.0 - np.asarray(height, np.float64))
    walk = _kernels()["walk"]
    rng = np.random.default_rng(seed)
    out = []
    for n, b in enumerate(bins(sectors, bands, max_angle)):
        v = directions(b, rays_per_bin, rng)
        out.append(walk(depth, np.ascontiguousarray(volumes[n]), *_rays(depth.shape, v, height_scale, rng), True))
    return np.concatenate(out)


def point_paths(depth: np.ndarray, point, view_dir, height_scale: float, visible_only: bool) -> np.ndarray:
    """Free path (texels) from one point (x, y in texels, texel i spanning [i, i + 1); t the layer depth) along each
    direction V (N, 3): to the first hit after the point; with ``visible_only`` inf where the ray through the point
    meets the relief before it (the direction cannot reach it from the top)."""
    rows, cols = np.shape(depth)
    x, y, t = point
    v = np.asarray(view_dir, np.float64)
    span = v[:, :2] / v[:, 2:3] * height_scale
    per_t = cols * np.sqrt((span ** 2).sum(axis=1) + height_scale ** 2)
    uv0 = np.array([x / cols, y / rows]) + t * span  # where the ray through the point enters the top plane
    ahead = first_hits(depth, uv0, v, height_scale, t_start=np.full(len(v), t))
    if not visible_only:
        return (ahead - t) * per_t
    from_top = first_hits(depth, uv0, v, height_scale)
    return np.where(from_top >= t - ROOT_SLACK, (ahead - t) * per_t, np.inf)
