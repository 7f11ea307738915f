"""The refined kind's direction bins and column lists: the constants of the bake, the bins of the view cone
(``bins``, ``volume_index``: which volume a ray reads) and each bin's column offsets sorted by rho (``entries``).
The GPU bake (``distance_refined.wgsl``) reads the same lists; cpu.py's docstring states the construction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from maptools.volume import cpu as dist

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
    (wgpuviewer/techniques/distance/distance.wgsl) decides it: the plain volume (last) when it is steeper than max_angle, else its
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
