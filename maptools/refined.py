"""The direction-binned refined distance map (Romanyuk et al. 2017, made to pay): CPU reference and the geometry its GPU bake
(``wgsl/maps/distance_refined.wgsl``) shares. docs/maps.md states the contract and the safety argument.

A tracer's ray keeps its direction, so it may read a value made for a *set* of directions containing its own. The
directions w (unit, metric, Z down) of the view cone (polar angle <= max_angle from the normal) are split into
bins: ``sectors`` equal sectors of the azimuth of w's horizontal part x ``bands`` polar bands of equal cosine ratio
(edge k at cos = cos(max_angle)^(k / bands): over a flat floor a bin's value is then the same fraction of its
rays' free path in every band). One volume per bin, plus the plain map as the last volume for rays steeper than
max_angle. With sectors = 1 and bands = 1 the single bin is the whole cone, and with ``visibility="on"`` as well
that is the refined map as the paper defines it (one value per voxel for the whole cone, only the directions that can
reach the voxel counted).

Value of voxel box B for bin Omega: a lower bound of the free path of every ray that starts in B with a direction
in Omega, i.e. of min |q - p| over p in B, q in the outer solid O, q - p in the cone K(Omega). For one sub-cell
column C = R x [T, inf) of O the differences q - p fill the box (R - B_h) x [T - bottom(B), inf): with rho = the
least horizontal length in (R - B_h) within the bin's azimuth wedge (voxel independent: a precomputed list of
column offsets sorted by rho), z0 = max(0, T - bottom(B)), and polar angles [a, b],

    |q - p| >= sqrt(r^2 + max(z0, r cot b)^2),    r = max(rho, z0 tan a)

(horizontal length >= rho and >= depth * tan a; depth >= z0 and >= horizontal * cot b). The value is the least
bound over the listed columns (offsets whose rho < ``reach``, near ones as sub-cells, far ones as whole cells,
whose column contains the sub-cells'), capped at reach / sin b (every unlisted column is farther than that), and
never below the plain value of B (a bound for every direction). No direction sampling, no march, no slack
beyond the store margin; closed form per column.

The paper's visibility condition (``visibility="on"``): a tracer reads B's value only at a point p it reached
through free space, so a direction w whose backward path from every point of B passes through the relief cannot
be the direction of a ray reading B, and need not bound B's value. Whether a backward path is blocked is decided
against the inner solid I (cell columns from the DEEPEST of the cell's four corners down: inside the bilinear
solid): at backward horizontal distance x along -u (u the azimuth of w), every point of B has risen by x cot
(polar) and lies over the footprint F shifted by -x u; if even B's top face is below every inner column those
shifted footprints touch (for every azimuth of the sector), every such path is inside the relief there. So with
M(x) the deepest inner top (largest Z) over the cells any shifted footprint touches,

    every w of the sector with cot(polar) < g = max over x of (top(B) - M(x)) / x   is blocked,

and the rays that can read B have polar angles <= arccot(g) (+ ANGLE_SLACK). A blocked-from-above direction is
monotone in the polar angle (a steeper backward path is higher at every x and the solid is a height field), so
this cut is the whole condition for the sampled x. The bake then uses [a, min(b, arccot(g))] as the band's polar
range for B: deep in a narrow pit only steep rays arrive, and a steep ray's bound past the pit walls is long.
x runs over HORIZON_STEP, 2 HORIZON_STEP, ... up to the reach; fewer x only finds fewer blocked directions (safe).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wgpuviewer.core.errors import UserError

from . import distance as dist

#: Total values (volumes x slices x W x H) the refined kind generates: the default 33 volumes (4 x 8 bins and the
#: plain one) of a 1024^2 map at 16 slices, 1056 MiB of float16. Memory, not speed, is what larger maps would buy:
#: fewer slices cost more fetches than the bins save (docs/maps.md, "Large height maps").
MAX_VALUES = 33 << 24
#: Bins are widened by this much (radians) in azimuth and polar angle: a float32 tracer that rounds a ray across a
#: bin edge still reads a value that holds for it.
ANGLE_SLACK = 1e-4
#: Column offsets whose whole cell is nearer than this (texels, horizontally within the bin) are listed as their
#: K x K sub-cells; farther ones as the whole cell (the cell-min column: a superset, so a weaker but safe bound).
NEAR_FIELD = 2.0
SECTOR_CHOICES = (1, 2, 4, 8, 16)
#: Most polar bands (the tracer computes a ray's band from the count alone).
MAX_BANDS = 16
#: A window of s x s cells is listed whole (its column: the highest of its cells') once it is at least
#: FAR_RATIO * s texels away within the bin; nearer ones are split.
FAR_RATIO = 4.0
#: Polar bands the GPU bake computes in one walk over a sector's columns (one per vec4 lane).
BANDS_PER_PASS = 4
#: The paper's visibility condition: off (every direction of a bin bounds a voxel) or on (only directions that can
#: reach the voxel unblocked from the top of the relief).
VISIBILITY_CHOICES = ("off", "on")
#: Backward horizontal distances (texels) at which a direction is tested for being blocked: multiples of this, up
#: to the reach.
HORIZON_STEP = 0.5


@dataclass(frozen=True)
class Bin:
    """A set of metric directions: azimuth (of the horizontal part) in [az_lo, az_hi] unless ``full``, polar angle
    in [polar_lo, polar_hi] (radians, slack included)."""

    az_lo: float
    az_hi: float
    full: bool
    polar_lo: float
    polar_hi: float

    @property
    def tan_lo(self) -> float:
        return math.tan(self.polar_lo)

    @property
    def cot_hi(self) -> float:
        return 1.0 / math.tan(self.polar_hi)

    @property
    def sin_hi(self) -> float:
        return math.sin(self.polar_hi)


def band_edges(bands: int, max_angle: float) -> list[float]:
    """Polar angles (radians) of the band edges 0 < e_1 < ... < e_(bands-1) < max_angle: cos e_k = cos(max)^(k/bands)."""
    c = math.cos(math.radians(max_angle))
    return [math.acos(c ** (k / bands)) for k in range(1, bands)]


def bins(sectors: int, bands: int, max_angle: float) -> list[Bin]:
    """The direction bins in volume order: index = band * sectors + sector; sector s holds the azimuths
    atan2(w_y, w_x) in [-pi + s 2pi/sectors, -pi + (s+1) 2pi/sectors]; band b the polar angles between its edges."""
    edges = [0.0, *band_edges(bands, max_angle), math.radians(max_angle)]
    width = 2 * math.pi / sectors
    out = []
    for b in range(bands):
        lo = max(edges[b] - ANGLE_SLACK, 0.0)
        hi = edges[b + 1] + ANGLE_SLACK
        for s in range(sectors):
            out.append(Bin(-math.pi + s * width - ANGLE_SLACK, -math.pi + (s + 1) * width + ANGLE_SLACK,
                           sectors == 1, lo, hi))
    return out


def volume_index(view_dir, sectors: int, bands: int, max_angle: float) -> np.ndarray:
    """The volume a ray with tangent-space view vector V (N, 3), V.z > 0, reads, decided as the tracer
    (wgsl/techniques/distance.wgsl) decides it: the plain volume (last) when it is steeper than max_angle, else its
    bin: the sector of the azimuth of (-V.x, -V.y) (sector 0 for a vertical ray), the band
    floor(bands * ln cos(polar) / ln cos(max_angle))."""
    v = np.atleast_2d(np.asarray(view_dir, np.float64))
    cos_polar = v[:, 2] / np.linalg.norm(v, axis=1)
    steep_cos = math.cos(math.radians(max_angle))
    sector = np.zeros(len(v), np.int64)
    if sectors > 1:
        az = np.arctan2(-v[:, 1], -v[:, 0])
        flat = (v[:, 0] == 0) & (v[:, 1] == 0)
        sector = np.where(flat, 0, np.clip(np.floor((az + math.pi) / (2 * math.pi) * sectors), 0, sectors - 1))
    band = np.zeros(len(v), np.int64)
    if bands > 1:
        with np.errstate(divide="ignore"):
            band = np.clip(np.floor(bands * np.log(cos_polar) / math.log(steep_cos)), 0, bands - 1)
    steep = cos_polar < steep_cos
    return np.where(steep, sectors * bands, band * sectors + sector).astype(np.int64)


# -- column offsets ----------------------------------------------------------------------------------

def wedge_rho(x0, x1, y0, y1, b: Bin) -> np.ndarray:
    """Least length of a horizontal vector in the rectangle [x0, x1] x [y0, y1] whose azimuth is in the bin's
    wedge (0 counts as in every wedge); inf where there is none. The least length over the rectangle is at its
    point nearest to 0 when that lies in the wedge; otherwise on one of the wedge's two edge rays, where it is
    the ray's entry into the rectangle (any wedge, convex or not)."""
    cx, cy = np.clip(0.0, x0, x1), np.clip(0.0, y0, y1)
    near = np.hypot(cx, cy)
    if b.full:
        return near
    mid, half = 0.5 * (b.az_lo + b.az_hi), 0.5 * (b.az_hi - b.az_lo)
    off = np.abs(np.mod(np.arctan2(cy, cx) - mid + math.pi, 2 * math.pi) - math.pi)
    out = np.where((off <= half) | (near == 0.0), near, np.inf)
    for az in (b.az_lo, b.az_hi):
        ux, uy = math.cos(az), math.sin(az)
        enter, leave = np.zeros_like(near), np.full_like(near, np.inf)
        for u, lo, hi in ((ux, x0, x1), (uy, y0, y1)):
            if u == 0.0:
                inside = (lo <= 0.0) & (hi >= 0.0)
                leave = np.where(inside, leave, -np.inf)
            else:
                t0, t1 = lo / u, hi / u
                enter = np.maximum(enter, np.minimum(t0, t1))
                leave = np.minimum(leave, np.maximum(t0, t1))
        out = np.where(enter <= leave, np.minimum(out, enter), out)
    return out


@dataclass(frozen=True)
class Entries:
    """The columns one bin's bake visits. ``level`` 0: a sub-cell, offset (ox, oy) from the voxel's own sub-cell
    (K i + ox, K j + oy); level L >= 1: the window of 2^(L-1) x 2^(L-1) cells from cell (i + ox, j + oy), whose column
    is the highest of its cells' (level 1 = one cell). A cell with ``children`` > 0 is a header: its sub-cells follow
    it and stand for it (the GPU looks at them only when the header's bound can beat the value). Headers and
    windows are sorted by rho, a lower bound for the children too."""

    ox: np.ndarray
    oy: np.ndarray
    level: np.ndarray
    children: np.ndarray
    rho: np.ndarray

    @property
    def final(self) -> np.ndarray:
        """The columns whose bounds make the value (everything but headers)."""
        return (self.level == 0) | (self.children == 0)

    @property
    def levels(self) -> int:
        return int(self.level.max())

    def packed(self, w: int, h: int, k: int) -> np.ndarray:
        """(N, 4) 32-bit words for the GPU: ox, oy modulo the period of their level (sub-cells: W K, H K; windows:
        W, H), level | children << 8, rho (f32 rounded down)."""
        sub = self.level == 0
        out = np.zeros((len(self.rho), 4), np.uint32)
        out[:, 0] = np.where(sub, np.mod(self.ox, w * k), np.mod(self.ox, w))
        out[:, 1] = np.where(sub, np.mod(self.oy, h * k), np.mod(self.oy, h))
        out[:, 2] = self.level | (self.children << 8)
        out[:, 3] = dist.round_down(self.rho, np.float32).view(np.uint32)
        return out


def entries(b: Bin, k: int, sy: float, reach: float) -> Entries:
    """The columns with rho < reach for bin ``b`` (K x K sub-cells per cell, row spacing sy): a quadtree over cell
    offsets from windows of the largest size down, a window kept whole once rho >= FAR_RATIO x its size, cells
    nearer than NEAR_FIELD split into their sub-cells. Every column within reach lies in exactly one final entry."""
    ax, ay = 0.5 + dist.BOX_GROW, 0.5 * sy + dist.BOX_GROW

    def rho(x, y, size_x, size_y, step_x):
        return wedge_rho(x * step_x - ax, (x + size_x) * step_x + ax, y * step_x * sy - ay,
                         (y + size_y) * step_x * sy + ay, b)

    size = 1 << max(0, math.ceil(math.log2(max(reach / FAR_RATIO, 1.0))))
    rx, ry = math.ceil(reach) + 1, math.ceil(reach / sy) + 1
    nx, ny = math.ceil((rx + 1) / size), math.ceil((ry + 1) / size)
    gy, gx = np.mgrid[-ny:ny + 1, -nx:nx + 1]
    x, y = gx.ravel() * size, gy.ravel() * size
    heads, rows = [], []  # rows: (ox, oy, level, rho) of final windows; heads: (ox, oy, rho) of near cells
    while x.size:
        r = rho(x, y, size, size, 1.0)
        inside = r < reach
        x, y, r = x[inside], y[inside], r[inside]
        whole = (r >= FAR_RATIO * size) if size > 1 else (r >= min(NEAR_FIELD, reach))
        level = int(math.log2(size)) + 1
        rows.append((x[whole], y[whole], np.full(whole.sum(), level), r[whole]))
        if size == 1:
            heads = (x[~whole], y[~whole], r[~whole])
            break
        half = size // 2
        x = (x[~whole][:, None] + np.array([0, half, 0, half])[None]).ravel()
        y = (y[~whole][:, None] + np.array([0, 0, half, half])[None]).ravel()
        size = half
    ox, oy, level, r = (np.concatenate(p) for p in zip(*rows))
    children = np.zeros(len(r), np.int64)
    groups = []  # per header: its sub-cells (ox, oy, rho) sorted by rho
    if len(heads) and heads[0].size:
        u, v = (a.ravel() for a in np.meshgrid(np.arange(k), np.arange(k), indexing="xy"))
        for hx, hy, hr in zip(*heads):
            sx, sy_ = k * hx + u, k * hy + v
            sr = rho(sx, sy_, 1, 1, 1.0 / k)
            keep = sr < reach
            order = np.argsort(sr[keep], kind="stable")
            groups.append((hx, hy, hr, sx[keep][order], sy_[keep][order], sr[keep][order]))
    groups = [g for g in groups if g[3].size]
    ox = np.concatenate([ox, [g[0] for g in groups]]).astype(np.int64)
    oy = np.concatenate([oy, [g[1] for g in groups]]).astype(np.int64)
    level = np.concatenate([level, np.ones(len(groups), np.int64)]).astype(np.int64)
    children = np.concatenate([children, [g[3].size for g in groups]]).astype(np.int64)
    r = np.concatenate([r, [g[2] for g in groups]])
    head_of = np.concatenate([np.full(len(r) - len(groups), -1), np.arange(len(groups))]).astype(np.int64)
    out = ([], [], [], [], [])
    for q in np.argsort(r, kind="stable"):
        for lst, val in zip(out, (ox[q], oy[q], level[q], children[q], r[q])):
            lst.append([val])
        if head_of[q] >= 0:
            g = groups[head_of[q]]
            n = g[3].size
            for lst, val in zip(out, (g[3], g[4], np.zeros(n, np.int64), np.zeros(n, np.int64), g[5])):
                lst.append(val)
    ox, oy, level, children, r = (np.concatenate(p) for p in out)
    return Entries(ox.astype(np.int64), oy.astype(np.int64), level.astype(np.int64), children.astype(np.int64),
                   r.astype(np.float64))


# -- the visibility condition ------------------------------------------------------------------------

def inner_tops(depth: np.ndarray) -> np.ndarray:
    """Top of the inner solid's column over each bilinear cell [i + 0.5, i + 1.5] x [j + 0.5, j + 1.5] (texels): the
    DEEPEST of its four corner depths (the bilinear patch is nowhere deeper), float64 (H, W) at [j, i]."""
    return dist.cell_corners(depth, np.maximum)


def ring_count(reach: float) -> int:
    """Backward distances tested: HORIZON_STEP, 2 HORIZON_STEP, ... up to the reach."""
    return int(math.floor(reach / HORIZON_STEP + 1e-9))


def horizon_rings(b: Bin, sy: float, reach: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per backward distance x = n HORIZON_STEP (n = 1, 2, ... up to the reach): the cell offsets (ox, oy) from a
    voxel's own cell whose cell the voxel's footprint, shifted by -x u for an azimuth u of ``b``'s wedge, can touch.
    The shifts f - q (f in the footprint, q in the cell) fill a rectangle; the cell is listed when the wedge's arc
    of radius x may meet it (its least length within the wedge <= x <= its farthest corner): a superset, so
    the deepest inner top over the list is never shallower than the one over the cells really touched (safe)."""
    g = dist.BOX_GROW
    n = ring_count(reach)
    rx, ry = math.ceil(reach) + 3, math.ceil(reach / sy) + 3
    oy, ox = (a.ravel() for a in np.mgrid[-ry:ry + 1, -rx:rx + 1])
    x0, x1 = -ox - 1.5 - g, -ox + 0.5 + g
    y0, y1 = -(oy + 1.5) * sy - g, -(oy - 0.5) * sy + g
    near = wedge_rho(x0, x1, y0, y1, b)
    far = np.hypot(np.maximum(np.abs(x0), np.abs(x1)), np.maximum(np.abs(y0), np.abs(y1)))
    out = []
    for step in range(1, n + 1):
        x = step * HORIZON_STEP
        on = (near <= x + 1e-9) & (far >= x - 1e-9)
        out.append((ox[on], oy[on]))
    return out


#: cot(ANGLE_SLACK): widening a polar angle arccot(g) by the slack gives cot = (g COT_SLACK - 1) / (g + COT_SLACK).
COT_SLACK = 1.0 / math.tan(ANGLE_SLACK)


def widened_cot(g):
    """cot(arccot(g) + ANGLE_SLACK) for g > 0, else 0 (no cut): the visibility cut widened as the bins are."""
    g = np.asarray(g, np.float64)
    return np.maximum((g * COT_SLACK - 1.0) / (g + COT_SLACK), 0.0)


def horizon(depth: np.ndarray, slices: int, height_scale: float, sectors: int, max_angle: float,
            reach: float, at: tuple | None = None) -> np.ndarray:
    """The visibility cut per sector and voxel, float64 (sectors, Dz, H, W): the cot of the largest polar angle of
    a ray of the sector that can reach the voxel box unblocked (widened by ANGLE_SLACK), 0 where nothing is cut.
    g = max over x of (top of the box - the deepest inner top over the x ring) / x (module docstring). ``at``:
    (slice, row, column) index arrays: the cut at those voxels only, (sectors, N)."""
    h, w = depth.shape
    sw = height_scale * w
    tops = inner_tops(depth) * sw
    box_tops = np.arange(slices, dtype=np.float64) * (sw / slices) - dist.BOX_GROW
    if at is None:
        rows, cols = np.arange(h), np.arange(w)
        above, shape = box_tops[:, None, None], (slices, h, w)
    else:
        kk, jj, ii = at
        above, shape = box_tops[kk], np.shape(kk)
    out = np.zeros((sectors, *shape))
    for s, b in enumerate(bins(sectors, 1, max_angle)):
        g = np.zeros(out.shape[1:])
        for n, (ox, oy) in enumerate(horizon_rings(b, w / h, reach), start=1):
            if not ox.size:
                continue
            if at is None:  # the whole map: one shifted copy of the tops per offset
                m = np.full((h, w), -np.inf)
                for dx, dy in zip(ox, oy):
                    np.maximum(m, tops[(rows + dy) % h][:, (cols + dx) % w], out=m)
            else:
                m = tops[(jj[:, None] + oy) % h, (ii[:, None] + ox) % w].max(axis=1)
            np.maximum(g, (above - m) / (n * HORIZON_STEP), out=g)
        out[s] = widened_cot(g)
    return out


def polar_top(b: Bin, reach: float, reach_cot: np.ndarray | None):
    """(cot, 1 / sin, reach / sin) of the largest polar angle of bin ``b``'s rays that can read each voxel: the
    bin's own where ``reach_cot`` (``horizon``'s, for the bin's sector) does not cut it, else arccot(reach_cot),
    but never below the bin's least polar angle (no ray of the bin reaches such a voxel; its value is then the
    bound for rays exactly at that angle). As the GPU bake computes them."""
    if reach_cot is None:
        return np.float64(b.cot_hi), np.float64(1.0 / b.sin_hi), np.float64(reach / b.sin_hi)
    cut = reach_cot > b.cot_hi
    cot = np.where(cut, reach_cot, b.cot_hi)
    cot = np.where(cot * b.tan_lo > 1.0, 1.0 / max(b.tan_lo, 1e-300), cot)
    inv_sin = np.where(cut, np.sqrt(1.0 + cot * cot), 1.0 / b.sin_hi)
    return cot, inv_sin, np.where(cut, reach * inv_sin, reach / b.sin_hi)


# -- the bake (CPU reference) --------------------------------------------------------------------------

#: Active voxels are compacted after this many columns (speed only).
_COMPACT_EVERY = 8


def bake(sub_tops: np.ndarray, windows: list[np.ndarray], plain: np.ndarray, b: Bin, e: Entries, k: int,
         bottoms: np.ndarray, reach: float, reach_cot: np.ndarray | None = None) -> np.ndarray:
    """One bin's volume (float64, before rounding): the least bound over the final columns of ``e``, capped at
    reach / sin b, floored at ``plain`` (the stored plain volume (Dz, H, W)). ``sub_tops`` (H K, W K) and
    ``windows`` (level L - 1 -> (H, W)) are column tops in metric Z, ``bottoms`` each slice's box bottom;
    ``reach_cot`` (Dz, H, W): the visibility condition's cut of the polar range per voxel (None: off)."""
    voxels = tuple(a.ravel() for a in np.indices(plain.shape))
    cut = None if reach_cot is None else reach_cot.ravel()
    return bake_at(sub_tops, windows, plain.astype(np.float64).ravel(), voxels, b, e, k, bottoms, reach,
                   cut).reshape(plain.shape)


def bake_at(sub_tops: np.ndarray, windows: list[np.ndarray], floor: np.ndarray, voxels: tuple, b: Bin, e: Entries,
            k: int, bottoms: np.ndarray, reach: float, reach_cot: np.ndarray | None = None) -> np.ndarray:
    """``bake``'s values (float64) at the voxels (slice, row, column) = ``voxels`` (flat index arrays) whose plain
    values are ``floor``; ``reach_cot``: their cuts (None: off). Each voxel's value depends on its own inputs only."""
    kk, jj, ii = voxels
    h, w = windows[0].shape
    cot_hi, inv_sin, best = (np.broadcast_to(a, floor.shape) for a in polar_top(b, reach, reach_cot))
    best = best.copy()
    active = np.arange(floor.size)
    tan_lo = b.tan_lo
    sub = sub_tops.ravel()
    order = np.flatnonzero(e.final)
    order = order[np.argsort(e.rho[order], kind="stable")]
    for n, q in enumerate(order):
        if n % _COMPACT_EVERY == 0:
            active = active[(best[active] > e.rho[q] * inv_sin[active]) & (best[active] > floor[active])]
        if not active.size:
            break
        j, i = jj[active], ii[active]
        if e.level[q] == 0:
            top = sub[((k * j + e.oy[q]) % (k * h)) * (k * w) + (k * i + e.ox[q]) % (k * w)]
        else:
            top = windows[e.level[q] - 1].ravel()[((j + e.oy[q]) % h) * w + (i + e.ox[q]) % w]
        z0 = np.maximum(top - bottoms[kk[active]], 0.0)
        r = np.maximum(e.rho[q], z0 * tan_lo)
        depth = np.maximum(z0, r * cot_hi[active])
        # voxels past their own exit (every later column is at least `bound` away) cannot lower their value
        best[active] = np.minimum(best[active], np.sqrt(r * r + depth * depth))
    return np.maximum(floor, best - dist.STORE_MARGIN)


def window_tops(depth: np.ndarray, levels: int, sw: float) -> list[np.ndarray]:
    """Column tops (metric Z) of the windows of 2^(L-1) x 2^(L-1) cells from cell (i, j), L = 1..levels: the least
    depth over the texels [i, i + 2^(L-1)] x [j, j + 2^(L-1)] (wrap), times S*W. Level 1 = the cells."""
    out = [dist.cell_tops(depth) * sw]
    for level in range(1, levels):
        s = 1 << (level - 1)
        t = out[-1]
        right = np.roll(t, -s, axis=1)
        out.append(np.minimum(np.minimum(t, right), np.minimum(np.roll(t, -s, axis=0), np.roll(right, -s, axis=0))))
    return out


#: What a maptools user can do about refined volumes beyond the limit (``check``'s default fix).
FEWER_VALUES = "downscale the height map or use fewer --slices, --sectors or --bands"


def check(w: int, h: int, slices: int, sectors: int, bands: int, kind: str = "distance_refined",
          fix: str = FEWER_VALUES) -> int:
    """Number of volumes (bins + the plain one), after checking the size limits: the refined kind's own total first
    (with the default 33 volumes the stricter one), then the plain volume it starts from. ``fix``: what the
    caller's user can change (maptools' options by default; the renderer names the height map's size)."""
    if sectors not in SECTOR_CHOICES:
        raise UserError(f"{kind}: option sectors={sectors}; expected one of {', '.join(map(str, SECTOR_CHOICES))}")
    volumes = sectors * bands + 1
    dist.check_volume(w, h, slices, kind, volumes, MAX_VALUES, "float16", fix)
    dist.check_volume(w, h, slices, kind, fix=fix if fix != FEWER_VALUES else dist.FEWER_SLICES)
    return volumes


def sample_reference(height: np.ndarray, index, *, slices: int = 16, height_scale: float = 0.05, subcells: int = 4,
                     max_angle: float = 85.0, sectors: int = 4, bands: int = 8, reach: float = 16.0,
                     visibility: str = "off") -> np.ndarray:
    """``distance_refined(height, ...)[index]`` for a tuple (volume, slice, row, column) of integer index arrays,
    computed at those voxels only: their plain values (``distance.sample_reference``), their cuts, and ``bake``'s
    walk over each bin's columns for the voxels of that bin, in the same float64 order."""
    hh, w = height.shape
    volumes = check(w, hh, slices, sectors, bands)
    dist.check_subcells(subcells, "distance_refined")
    check_visibility(visibility)
    index = dist.index_arrays(index, (volumes, slices, hh, w))
    vv, kk, jj, ii = (a.ravel() for a in index)
    out = np.zeros(vv.shape, np.float16)
    if not vv.size:
        return out.reshape(index[0].shape)
    depth = 1.0 - height.astype(np.float64)
    sw = height_scale * w
    floor = dist.sample_reference(height, (kk, jj, ii), slices=slices, height_scale=height_scale,
                                  subcells=subcells).astype(np.float64)
    plain = vv == volumes - 1
    out[plain] = dist.round_down(floor[plain], np.float16)
    binned = np.flatnonzero(~plain)
    if binned.size:
        directions = bins(sectors, bands, max_angle)
        lists = {v: entries(directions[v], subcells, w / hh, reach) for v in np.unique(vv[binned]).tolist()}
        windows = window_tops(depth, max(e.levels for e in lists.values()), sw)
        sub_tops = dist.subcell_tops(depth, subcells) * sw
        bottoms = dist.box_bottoms(slices, height_scale, w)
        cuts = None
        if visibility == "on":
            cuts = horizon(depth, slices, height_scale, sectors, max_angle, reach, at=(kk[binned], jj[binned],
                                                                                       ii[binned]))
        for v, e in lists.items():
            mine = vv[binned] == v
            at = binned[mine]
            cut = None if cuts is None else cuts[v % sectors][mine]
            values = bake_at(sub_tops, windows, floor[at], (kk[at], jj[at], ii[at]), directions[v], e, subcells,
                             bottoms, reach, cut)
            out[at] = dist.round_down(values, np.float16)
    return out.reshape(index[0].shape)


def check_visibility(visibility: str) -> None:
    if visibility not in VISIBILITY_CHOICES:
        raise UserError(f"distance_refined: option visibility={visibility!r}; expected one of "
                        f"{', '.join(VISIBILITY_CHOICES)}")


def distance_refined(height: np.ndarray, *, slices: int = 16, height_scale: float = 0.05, subcells: int = 4,
                     max_angle: float = 85.0, sectors: int = 4, bands: int = 8, reach: float = 16.0,
                     visibility: str = "off", progress: bool = True) -> np.ndarray:
    """Direction-binned refined volumes, float16 (V, Dz, H, W) rounded down: volume band * sectors + sector for
    the rays of that bin, the last one the plain map (rays steeper than max_angle). ``visibility`` "on": each
    voxel bounded only for the directions that can reach it unblocked (the paper's condition)."""
    from tqdm import tqdm

    hh, w = height.shape
    check(w, hh, slices, sectors, bands)
    dist.check_subcells(subcells, "distance_refined")
    check_visibility(visibility)
    depth = 1.0 - height.astype(np.float64)
    sw = height_scale * w
    plain = dist.store(dist.box_distance(depth, slices, height_scale, subcells))
    sub_tops = dist.subcell_tops(depth, subcells) * sw
    bottoms = dist.box_bottoms(slices, height_scale, w)
    lists = [entries(b, subcells, w / hh, reach) for b in bins(sectors, bands, max_angle)]
    windows = window_tops(depth, max(e.levels for e in lists), sw)
    cuts = horizon(depth, slices, height_scale, sectors, max_angle, reach) if visibility == "on" else None
    out = []
    for n, (b, e) in enumerate(tqdm(list(zip(bins(sectors, bands, max_angle), lists)), desc="distance_refined (cpu)",
                                    unit="bin", disable=None if progress else True, leave=False)):
        cut = None if cuts is None else cuts[n % sectors]
        out.append(dist.round_down(bake(sub_tops, windows, plain, b, e, subcells, bottoms, reach, cut), np.float16))
    out.append(dist.round_down(plain.astype(np.float64), np.float16))
    return np.stack(out)
