"""The direction-binned refined distance map (Romanyuk et al. 2017, made to pay): CPU reference and the geometry its GPU bake
(``distance_refined.wgsl``, beside it) shares; the bins and column lists are in ``bins``, the visibility
condition in ``visibility``. docs/maps.md states the contract and the safety argument.

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

import numpy as np

from maptools.volume import cpu as dist
from wgpuviewer.core.errors import UserError

from .bins import SECTOR_CHOICES, VISIBILITY_CHOICES, Bin, Entries, bins, entries
from .visibility import horizon

#: Total values (volumes x slices x W x H) the refined kind generates: the default 33 volumes (4 x 8 bins and the
#: plain one) of a 1024^2 map at 16 slices, 1056 MiB of float16. Memory, not speed, is what larger maps would buy:
#: fewer slices cost more fetches than the bins save (docs/maps.md, "Large height maps").
MAX_VALUES = 33 << 24


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
