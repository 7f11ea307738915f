"""CPU reference for the relaxed cone map (``cone`` kind; Policarpo & Oliveira 2007), conservative for the
BILINEAR surface (docs/maps.md, "Relaxed cone map": metric, tracer rule and the proof sketched here).

Horizontal metric: X = u*W, Y = v*W (texels of u; one row spans sy = W/H), depth in layer units t.
Stored value c(q) (float32 (H, W)), the cone ratio in **texels per unit of t** (one unit of t = the whole depth
range = S*W texels of the distance-map metric; so c does not depend on height_scale).

Guarantee: for every point p of texel q's footprint F_q = [i, i+1] x [j, j+1]*sy and every t < D(p), every ray
segment starting at (p, t) that stays inside the upward cone  K = {(x, s): |x - p| <= c (D(p) - s)}  has no
solid -> free transition (it enters the relief at most once and never leaves it).

An exit at surface point x needs D to increase along the (outward, radial) ray direction e at x, i.e. a
positive forward directional derivative. The computation visits bilinear cells C (between 4 texel centres):

* far cells: C may contain an exit point only if h(d) = max(dx a0, dx a1) + max(dy b0, dy b1) > 0 for some
  displacement d in R = C - F_q (a0, a1 / b0, b1: the cell's edge slopes in x / y; h is convex and positively
  homogeneous, so the test is exact at R's four corners); then every point x of C satisfies
  |x - p| >= rho(C) = dist(F_q, C) and D(p) - D(x) <= M_q - min corner(C)  (M_q = max D over the 3x3 texels
  around q, >= the bilinear D anywhere in F_q), so c < rho / (M_q - min corner) keeps C outside the cone;
* the 4 cells overlapping F_q (rho = 0): D is G-Lipschitz on their (convex) union, G = max gradient bound of
  the four, so D(p) - D(x) <= G |x - p| and c < 1/G leaves no surface point other than the apex in the cone.

c(q) = min(max_ratio, bounds) * (1 - STORE_MARGIN). filter="bilinear" then takes the min over the 3x3 texels
around each texel, which keeps a bilinear lookup of the map (a mix of the 4 texels around p, all neighbours of
p's own texel) below the nearest-lookup value. Each texel's ring walk stops once no further ring can lower its
value, as on the GPU. ``cone`` shows a progress bar on a terminal once it has taken a second (texels settled: the
ring walk of a 2048x2048 map takes tens of seconds).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from maptools.volume.cpu import index_arrays
from wgpuviewer.core.commands import terminal_progress
from wgpuviewer.core.errors import UserError

#: Relative margin every stored ratio loses (covers float32 arithmetic on the GPU and the float32 store).
STORE_MARGIN = 2.0 ** -12
#: An exit test h(d) within this relative band of 0 counts as "may exit" (safe side; CPU and GPU then agree).
EXIT_BAND = 1e-6
FILTERS = ("bilinear", "nearest")
#: Most rings (Chebyshev index rings around a texel) the search may visit: bounds the GPU kernel.
MAX_RINGS = 4096


def depth_of(height: np.ndarray) -> np.ndarray:
    """D = 1 - H, computed in float32 exactly like the GPU kernel, returned as float64."""
    return (np.float32(1.0) - np.asarray(height, np.float32)).astype(np.float64)


def ring_count(max_ratio: float, w: int, h: int) -> int:
    """Rings 0..n-1 cover every cell with rho < max_ratio (ring a has rho >= (a - 0.5) * min(1, W/H))."""
    return int(math.ceil(max_ratio / min(1.0, w / h) + 0.5)) + 1


def check(w: int, h: int, max_ratio: float) -> None:
    n = ring_count(max_ratio, w, h)
    if n > MAX_RINGS:
        raise UserError(f"cone: a {w}x{h} map with max_ratio {max_ratio:g} needs {n} search rings (more than "
                        f"{MAX_RINGS}); use a smaller --max-ratio or a less elongated map")


def ring_offsets(a: int) -> list[tuple[int, int]]:
    """Cell offsets (di, dj) of ring a: max(ax, ay) == a with ax = di if di >= 0 else -di - 1 (same for y)."""
    out = [(di, dj) for dj in (-a - 1, a) for di in range(-a - 1, a + 1)]
    out += [(di, dj) for dj in range(-a, a) for di in (-a - 1, a)]
    return out


def _axis_rho(d: int) -> float:
    """Distance along one axis between footprint [0, 1] and cell [d + 0.5, d + 1.5] (in cell units)."""
    return max(0.0, d - 0.5, -d - 1.5)


def cell_fields(depth: np.ndarray, sy: float) -> dict[str, np.ndarray]:
    """Per cell (indexed by its corner texel (row j, col i) = c00): min corner, slope ranges, gradient bound."""
    c00 = depth
    c10 = np.roll(depth, -1, axis=1)
    c01 = np.roll(depth, -1, axis=0)
    c11 = np.roll(c10, -1, axis=0)
    a0, a1 = c10 - c00, c11 - c01
    b0, b1 = (c01 - c00) / sy, (c11 - c10) / sy
    amag = np.maximum(np.abs(a0), np.abs(a1))
    bmag = np.maximum(np.abs(b0), np.abs(b1))
    return {"cmin": np.minimum(np.minimum(c00, c10), np.minimum(c01, c11)),
            "amax": np.maximum(a0, a1), "amin": np.minimum(a0, a1),
            "bmax": np.maximum(b0, b1), "bmin": np.minimum(b0, b1),
            "mag": amag + bmag, "grad": np.sqrt(amag * amag + bmag * bmag)}


def _neigh(a: np.ndarray, op, offsets) -> np.ndarray:
    out = a.copy()
    for dy, dx in offsets:
        op(out, np.roll(a, (dy, dx), axis=(0, 1)), out=out)
    return out


def _n3x3(a: np.ndarray, op) -> np.ndarray:
    return _neigh(a, op, [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dy or dx])


def raw_ratio(depth: np.ndarray, max_ratio: float, rows=None, cols=None,
              progress: Callable[[int, int], None] = lambda done, total: None) -> np.ndarray:
    """Nearest-lookup cone ratio (float64, before the store margin) for depth (H, W) float64: (H, W), or only at the
    texels (rows, cols) when given (index arrays; shaped like rows, each value exactly the whole map's). Each texel
    walks the rings until (a - 0.5) min(1, sy) >= c (M_q - global min depth): no farther cell can lower its ratio
    (the GPU's rule). ``progress(settled, texels)`` hears before each ring how many texels have stopped walking."""
    h, w = depth.shape
    sy = w / h
    shape = (h, w) if rows is None else np.shape(rows)
    if rows is None:
        rows, cols = (a.ravel() for a in np.indices((h, w)))
    rows, cols = np.asarray(rows, np.int64).ravel(), np.asarray(cols, np.int64).ravel()
    cf = {name: f.ravel() for name, f in cell_fields(depth, sy).items()}
    m = _n3x3(depth, np.maximum)[rows, cols]                 # M_q: max D over the footprint's 4 cells
    g = _neigh(cf["grad"].reshape(h, w), np.maximum, [(0, 1), (1, 0), (1, 1)])[rows, cols]  # cells around q
    reach = m - depth.min()                                  # M_q - global min depth
    c = np.full(rows.shape, float(max_ratio))
    live = np.arange(rows.size)                              # texels still walking
    for a in range(ring_count(max_ratio, w, h)):
        if a >= 1:
            live = live[(a - 0.5) * min(1.0, sy) < c[live] * reach[live]]
            if not live.size:
                break
        progress(rows.size - live.size, rows.size)
        r, q, m_live = rows[live], cols[live], m[live]
        for di, dj in ring_offsets(a):
            cell = ((r + dj) % h) * w + (q + di) % w
            cmin, mag = cf["cmin"][cell], cf["mag"][cell]
            xs, ys = (di - 0.5, di + 1.5), ((dj - 0.5) * sy, (dj + 1.5) * sy)
            # h is separable (x part + y part), so its max over R's corners is the sum of the two maxima
            hx = [x * (cf["amax"][cell] if x >= 0 else cf["amin"][cell]) for x in xs]
            hy = [y * (cf["bmax"][cell] if y >= 0 else cf["bmin"][cell]) for y in ys]
            hmax = np.maximum(hx[0], hx[1]) + np.maximum(hy[0], hy[1])
            band = EXIT_BAND * mag * (max(abs(xs[0]), abs(xs[1])) + max(abs(ys[0]), abs(ys[1])) + 1.0)
            denom = m_live - cmin
            may_exit = (mag > 0) & (hmax > -band) & (denom > 0)
            if di in (-1, 0) and dj in (-1, 0):
                with np.errstate(divide="ignore"):
                    bound = np.where(may_exit, 1.0 / g[live], np.inf)
            else:
                rho = math.hypot(_axis_rho(di), _axis_rho(dj) * sy)
                with np.errstate(divide="ignore", invalid="ignore"):
                    bound = np.where(may_exit, rho / np.where(denom > 0, denom, 1.0), np.inf)
            c[live] = np.minimum(c[live], bound)
    return c.reshape(shape)


def to_float32_down(a: np.ndarray) -> np.ndarray:
    """float64 -> float32, never rounding up."""
    f = a.astype(np.float32)
    up = f.astype(np.float64) > a
    f[up] = np.nextafter(f[up], np.float32(0))
    return f


def finish(raw: np.ndarray, filter: str) -> np.ndarray:
    c = raw * (1.0 - STORE_MARGIN)
    if filter == "bilinear":
        c = _n3x3(c, np.minimum)
    return to_float32_down(np.maximum(c, 0.0))


def cone(height: np.ndarray, *, max_ratio: float = 16.0, filter: str = "bilinear") -> np.ndarray:
    """Relaxed cone ratios, float32 (H, W), texels of u per unit of layer depth t (docs/maps.md)."""
    _check_options(height, max_ratio, filter)
    with terminal_progress("cone (CPU)", unit="texel") as progress:
        raw = raw_ratio(depth_of(height), max_ratio, progress=lambda done, total: progress("", done, total))
    return finish(raw, filter)


def _check_options(height: np.ndarray, max_ratio: float, filter: str) -> None:
    if filter not in FILTERS:
        raise UserError(f"cone: filter {filter!r}; expected one of {', '.join(FILTERS)}")
    hh, w = height.shape
    check(w, hh, max_ratio)


def sample_reference(height: np.ndarray, index, *, max_ratio: float = 16.0, filter: str = "bilinear") -> np.ndarray:
    """``cone(height, ...)[index]`` for a tuple (row, column) of integer index arrays, computed at those texels
    (and, for the bilinear filter, their 3 x 3 neighbours) only."""
    _check_options(height, max_ratio, filter)
    h, w = height.shape
    rows, cols = index_arrays(index, (h, w))
    around = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1)] if filter == "bilinear" else [(0, 0)]
    near = np.stack([((rows.ravel() + dy) % h) * w + (cols.ravel() + dx) % w for dy, dx in around])
    texels, where = np.unique(near, return_inverse=True)
    raw = raw_ratio(depth_of(height), max_ratio, texels // w, texels % w)
    c = (raw * (1.0 - STORE_MARGIN))[where.reshape(near.shape)].min(axis=0)  # the 3 x 3 min of finish()
    return to_float32_down(np.maximum(c, 0.0)).reshape(rows.shape)
