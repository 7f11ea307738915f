"""The plain 3D distance map (Donnelly), box-exact on a sub-cell outer solid: the CPU reference of the ``distance``
kind, and the geometry the ``distance_refined`` kind (whose last volume is this map) shares with it. docs/maps.md
states the contract and the safety argument.

Metric ("texel metric"). A W x H height map with height_scale S and Dz slices spans the periodic box
[0, W) x [0, W) x [0, S*W] of metric space: X = u*W, Y = v*W, Z = t*S*W (t = layer depth, Z grows downwards).
One unit = one texel along u; a texel row spans sy = W/H units (the tangent frame is isotropic in UV units).
Voxel (i, j, k) is the box [i, i+1] x [j, j+1]*sy x [k, k+1]*dz, dz = S*W/Dz.

Outer solid O. Each bilinear cell (between four texel centres) is split into K x K sub-cells; sub-cell (a, b)
covers X in [0.5 + a/K, 0.5 + (a+1)/K] (rows likewise, times sy) and carries the column rect x [T, inf) with
T = the least depth at its four corners. The bilinear patch restricted to a sub-rectangle is bilinear, so its
minimum is at a corner: O contains the relief solid {t >= D(u, v)}. K = 1 is the cell-min solid of Donnelly's
construction; larger K hugs slopes more closely.

Plain value of a voxel = the exact distance from the whole (slightly grown) voxel box to O. A tracer at any point
p of the box may step that far in any direction: safe for a NEAREST lookup anywhere in the box. (It is not safe
for a trilinear lookup, which mixes in the values of neighbouring boxes.) The distance is a separable
generalised distance transform over the sub-cell columns, computed exactly: per axis the gap between the box's
interval and a sub-cell's interval, per column the vertical gap from the box's bottom down to T.
"""

from __future__ import annotations

import math

import numpy as np

from maptools.registry import Option
from wgpuviewer.core.errors import UserError

#: Largest plain volume (W * H * slices) generated: 2^26 voxels = 256 MiB of float32 (2048x2048x16).
MAX_VOXELS = 1 << 26
#: Subtracted from every stored distance (texels): covers float32 rounding of the build and of the tracer's arithmetic.
STORE_MARGIN = 1e-3
#: Every voxel box is grown by this much (texels) on each side: a tracer's float32 position a hair outside the box
#: its nearest lookup picked is still inside the box the value was computed for.
BOX_GROW = 1e-3
#: Sub-cell counts per cell side the kinds accept (the GPU's intermediate buffers grow with K).
SUBCELLS = (1, 2, 4, 8)


# -- geometry ---------------------------------------------------------------------------------------

def spacing(w: int, h: int, slices: int, height_scale: float) -> tuple[float, float, float]:
    """Voxel spacing (sx, sy, sz) in texel-metric units: 1, W/H, S*W/Dz."""
    return 1.0, w / h, height_scale * w / slices


#: What a maptools user can do about a volume beyond its limit (``check_volume``'s default fix).
FEWER_SLICES = "downscale the height map or use fewer --slices"


def check_volume(w: int, h: int, slices: int, kind: str = "distance", volumes: int = 1, limit: int = MAX_VOXELS,
                 unit: str = "float32", fix: str = FEWER_SLICES) -> None:
    """A UserError when ``volumes`` volumes of w x h x slices hold more than ``limit`` values; ``fix`` names what the
    caller's user can change (maptools' options by default; the renderer names the height map's size)."""
    n = w * h * slices * volumes
    if n > limit:
        what = f"{volumes} volumes of {w}x{h}x{slices} hold" if volumes > 1 else f"a {w}x{h}x{slices} volume holds"
        raise UserError(f"{kind}: {what} {n} values, more than the limit {limit} ({unit}); {fix}")


def vertex_depth(depth: np.ndarray, k: int) -> np.ndarray:
    """The bilinear depth (repeat addressing) at the sub-cell vertices X = 0.5 + a/K, Y = (0.5 + b/K) sy:
    float64 (H*K, W*K), [b, a]."""
    h, w = depth.shape

    def axis(n):
        a = np.arange(n * k)
        return a // k, (a // k + 1) % n, (a % k) / k

    x0, x1, fx = axis(w)
    y0, y1, fy = axis(h)
    d = np.asarray(depth, np.float64)
    along_u = d[:, x0] * (1 - fx) + d[:, x1] * fx  # (H, W K): rows are interpolated after, each value as before
    return along_u[y0] * (1 - fy)[:, None] + along_u[y1] * fy[:, None]


def subcell_tops(depth: np.ndarray, k: int) -> np.ndarray:
    """Tops T (layer depth t) of the outer solid's sub-cell columns: the least depth at each sub-cell's four
    corners, float64 (H*K, W*K); sub-cell [b, a] covers X in [0.5 + a/K, 0.5 + (a+1)/K] (rows likewise)."""
    v = vertex_depth(depth, k)
    out = v.copy()
    for shift in ((0, 1), (1, 0), (1, 1)):
        np.minimum(out, np.roll(v, (-shift[0], -shift[1]), axis=(0, 1)), out=out)
    return out


def cell_corners(depth: np.ndarray, reduce=np.minimum) -> np.ndarray:
    """``reduce`` (np.minimum / np.maximum) of each bilinear cell's four corner depths, float64 (H, W) at [j, i]:
    the cell [i + 0.5, i + 1.5] x [j + 0.5, j + 1.5] (texels), wrapping."""
    d = np.asarray(depth, np.float64)
    right = np.roll(d, -1, axis=1)
    return reduce(reduce(d, right), reduce(np.roll(d, -1, axis=0), np.roll(right, -1, axis=0)))


def cell_tops(depth: np.ndarray) -> np.ndarray:
    """Top of each whole bilinear cell (the outer solid's column): the least of its four corner depths. Equals the
    minimum over the cell's sub-cell tops for every K."""
    return cell_corners(depth, np.minimum)


def interval_gap(lo, hi, half):
    """Distance from 0 to the interval [lo - half, hi + half] (the interval grown by a box's half-extent)."""
    return np.maximum(0.0, np.maximum(lo - half, -(hi + half)))


def subcell_gap(o, k: int, step: float):
    """Gap along one axis between a voxel box (half-extent step/2 + BOX_GROW) and the sub-cell K*n + o of its own
    index n: relative to the voxel centre that sub-cell covers [o/K, (o+1)/K] * step."""
    o = np.asarray(o, np.float64)
    return interval_gap(o / k * step, (o + 1) / k * step, 0.5 * step + BOX_GROW)


def box_bottoms(slices: int, height_scale: float, w: int) -> np.ndarray:
    """Z of the bottom face of each slice's (grown) voxel box."""
    dz = height_scale * w / slices
    return (np.arange(slices, dtype=np.float64) + 1.0) * dz + BOX_GROW


# -- the plain map ----------------------------------------------------------------------------------

def _gdt_axis(f: np.ndarray, k: int, n: int, step: float) -> np.ndarray:
    """out[..., i] = min over offsets o of subcell_gap(o)^2 + f[..., (K i + o) mod (n K)] along the last axis
    (length n K in, n out): exact. Offsets are taken in pairs (o, -1 - o) of equal gap, outwards, and stop once the
    gap alone reaches every current value."""
    nk = f.shape[-1]
    base = k * np.arange(n)
    out = np.full(f.shape[:-1] + (n,), np.inf)
    for o in range(nk // 2 + 1):
        g2 = float(subcell_gap(o, k, step)) ** 2
        if g2 >= out.max():
            break
        for off in (o, -1 - o):
            np.minimum(out, f[..., (base + off) % nk] + g2, out=out)
    return out


def box_distance(depth: np.ndarray, slices: int, height_scale: float, k: int) -> np.ndarray:
    """Exact distance (float64, (Dz, H, W)) from every grown voxel box to the outer solid of K x K sub-cells."""
    h, w = depth.shape
    sw = height_scale * w
    tops = subcell_tops(depth, k) * sw
    out = np.empty((slices, h, w))
    for z, bottom in enumerate(box_bottoms(slices, height_scale, w)):
        f = np.maximum(tops - bottom, 0.0) ** 2        # (H K, W K): vertical gap of each sub-cell column
        f = _gdt_axis(f, k, w, 1.0)                   # (H K, W): + the gap along u
        f = _gdt_axis(f.T, k, h, w / h).T             # (H, W): + the gap along v
        out[z] = np.sqrt(f)
    return out


def store(d: np.ndarray) -> np.ndarray:
    """Stored (safe) value: max(0, d - STORE_MARGIN), float32 rounded towards 0 (never above d - margin)."""
    v = np.maximum(np.asarray(d, np.float64) - STORE_MARGIN, 0.0)
    return round_down(v, np.float32)


def round_down(v: np.ndarray, dtype) -> np.ndarray:
    """Non-negative float64 values as ``dtype`` (float32 / float16), each rounded down (never above the input)."""
    out = v.astype(dtype)
    over = out.astype(np.float64) > v
    out[over] = np.nextafter(out[over], dtype(0))
    return out


def check_subcells(k: int, kind: str) -> None:
    if k not in SUBCELLS:
        raise UserError(f"{kind}: option subcells={k}; expected one of {', '.join(map(str, SUBCELLS))}")


def distance(height: np.ndarray, *, slices: int = 16, height_scale: float = 0.05, subcells: int = 4) -> np.ndarray:
    """Distance volume, float32 (Dz, H, W): per voxel a safe step (texel metric) for a nearest lookup anywhere in
    the voxel, in any direction: the distance from the voxel box to the outer solid of ``subcells``^2 sub-cells."""
    hh, w = height.shape
    check_volume(w, hh, slices)
    check_subcells(subcells, "distance")
    depth = 1.0 - height.astype(np.float64)
    return store(box_distance(depth, slices, height_scale, subcells))


# -- the plain map at given voxels ------------------------------------------------------------------

def index_arrays(index, shape: tuple[int, ...]) -> tuple[np.ndarray, ...]:
    """A tuple of integer index arrays into an array of ``shape`` as non-negative int64 arrays of one broadcast
    shape (negative entries count from the end, as numpy's indexing does); an IndexError for one out of range."""
    if len(index) != len(shape):
        raise IndexError(f"expected {len(shape)} index arrays, got {len(index)}")
    out = []
    for a, n in zip(np.broadcast_arrays(*(np.asarray(a) for a in index)), shape):
        if a.size and not np.issubdtype(a.dtype, np.integer):
            raise IndexError(f"index arrays must be integers, got {a.dtype}")
        a = a.astype(np.int64)
        if a.size and (a.min() < -n or a.max() >= n):
            raise IndexError(f"index out of range for an axis of length {n}")
        out.append(a % n if n else a)
    return tuple(out)


def _pair_gaps(n: int, k: int, step: float) -> tuple[np.ndarray, np.ndarray]:
    """The offsets ``_gdt_axis`` visits along an axis of n K sub-cells, in its order (o, -1 - o for o = 0, 1, ...),
    and their squared gaps, computed as it computes them."""
    pairs = n * k // 2 + 1
    offsets = np.stack([np.arange(pairs), -1 - np.arange(pairs)], axis=1).ravel()
    g2 = np.repeat([float(subcell_gap(o, k, step)) ** 2 for o in range(pairs)], 2)
    return offsets, g2


def sample_reference(height: np.ndarray, index, *, slices: int = 16, height_scale: float = 0.05,
                     subcells: int = 4) -> np.ndarray:
    """``distance(height, ...)[index]`` for a tuple (slice, row, column) of integer index arrays, computed at those
    voxels only. Per voxel the least candidate (vertical gap^2 + gap^2 along u) + gap^2 along v over the same
    sub-cell columns and offsets as the separable transform, in the same float64 order: a window of columns around
    the voxel, grown until every column outside it is provably no nearer (its gaps alone, plus the slice's least
    vertical gap, reach the value)."""
    hh, w = height.shape
    check_volume(w, hh, slices)
    check_subcells(subcells, "distance")
    kk, jj, ii = index_arrays(index, (slices, hh, w))
    k = subcells
    tops = subcell_tops(1.0 - height.astype(np.float64), k) * (height_scale * w)
    bottoms = box_bottoms(slices, height_scale, w)
    off_x, g2_x = _pair_gaps(w, k, 1.0)
    off_y, g2_y = _pair_gaps(hh, k, w / hh)
    least_top = tops.min()
    out = np.array([_window_min(tops, k, bottoms[z], least_top, j, i, off_x, g2_x, off_y, g2_y)
                    for z, j, i in zip(kk.ravel(), jj.ravel(), ii.ravel())])
    return store(np.sqrt(out)).reshape(kk.shape)


def _window_min(tops, k, bottom, least_top, j, i, off_x, g2_x, off_y, g2_y) -> float:
    """min over the sub-cell columns (K j + oy, K i + ox) of (vertical gap^2 + gx^2) + gy^2 (``sample_reference``):
    a window of offsets reaching ``reach`` texels each way, doubled until no column outside it can be lower."""
    nky, nkx = tops.shape
    least = np.square(max(least_top - bottom, 0.0))  # no column's vertical gap is smaller (squared alike)
    reach = 1.0
    while True:
        nx = min(len(off_x), 2 * math.ceil(reach * k))
        ny = min(len(off_y), 2 * math.ceil(reach * nky / nkx * k))
        window = tops[(k * j + off_y[:ny]) % nky][:, (k * i + off_x[:nx]) % nkx]
        best = ((np.maximum(window - bottom, 0.0) ** 2 + g2_x[:nx]) + g2_y[:ny, None]).min()
        # a column outside the window: its gap along u or along v alone is at least the next offset's
        outside = min(least + g2_x[nx] if nx < len(off_x) else np.inf,
                      least + g2_y[ny] if ny < len(off_y) else np.inf)
        if best <= outside:
            return float(best)
        reach *= 2.0


# -- what both kinds' registry entries share -------------------------------------------------------------

#: Plain distance volumes: absolute difference in texel-metric units (float32 GPU arithmetic vs float64 CPU; measured
#: <= 1e-5 on lavapipe). Far below the STORE_MARGIN (1e-3) that every stored value already subtracts for rounding.
DISTANCE_TOL = 1e-4

#: The options of both distance kinds.
VOLUME_OPTIONS = (
    Option("slices", 16, int, "depth slices Dz of the volume (t in [0, 1])", lo=1, hi=256),
    Option("height_scale", 0.05, float, "relief depth S in UV units the map is built for (metric: depth x S*W)",
           lo=1e-3, hi=1.0),
    Option("subcells", 4, int, "sub-cells per bilinear cell side of the outer solid (1 = the cell-min solid)",
           choices=SUBCELLS),
)
