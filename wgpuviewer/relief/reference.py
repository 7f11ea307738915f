"""Float64 reference: the exact first hit of a view ray with a bilinear height field.

Convention (tangent space): x = u, y = v, z = surface normal. The relief lies *below* the surface
plane z = 0. Maps store height H in [0, 1] (1 = top); this module works on depth D = 1 - H, an
array of shape (rows, cols) = (H_px, W_px) whose row index is v and column index is u. Texel
(col i, row j) has its centre at u = (i + 0.5) / W, v = (j + 0.5) / H.

The view direction V (tangent space) points from the surface point towards the eye, so V.z > 0
when the surface faces the viewer. A ray entering the surface at uv0 moves as

    uv(t) = uv0 - t * (V.xy / V.z) * S,        t = layer depth in [0, 1], S = height_scale,

and the exact hit is the smallest t >= 0 with t >= D(uv(t)), where D is sampled like a GPU
sampler with ideal (float64) bilinear filtering between texel centres and REPEAT (wrap) or
CLAMP (clamp-to-edge) addressing. Since D <= 1, such a t exists in [0, 1].

Algorithm: in texel coordinates x = u * W - 0.5, y = v * H - 0.5 the sampled D is bilinear inside
each cell [cx, cx+1] x [cy, cy+1] between four texel centres, and the ray is a straight line, so
along the ray D is a quadratic in t within each cell. The rays walk the cells they cross with a
2D DDA; in each cell f(t) = t - D(t) is solved for its smallest root inside the cell's t-interval
(or the entry point itself when f >= 0 there). The first cell that yields a root gives t*. This
is exact up to float64 rounding: thin features (a one-texel spike crossed at a grazing angle) are
never stepped over, unlike any fixed-step search. Rays are vectorised: the loop runs over cell
steps with arrays over the rays still walking; finished rays leave the active set.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np

from wgpuviewer.core.errors import InputError
from wgpuviewer.core.sampling import bilinear, check_address, wrap_index

#: Default bound on the cells one ray may need (see exact_hit): 89.9 degrees on a 256^2 map with
#: S = 0.05 needs ~10^4; V.z -> 0 needs unboundedly many, and would hang instead of failing.
MAX_CELLS = 1_000_000

# Roots computed a hair outside a cell's t-interval are rounding, not misses: absorb them (in t).
_ROOT_SLACK = 1e-12


@dataclass
class Hit:
    """Result of :func:`exact_hit` for N rays."""

    uv: np.ndarray  # (N, 2) float64 raw hit uv (not wrapped; NaN where invalid)
    t: np.ndarray  # (N,) float64 hit depth in [0, 1] (NaN where invalid)
    valid: np.ndarray  # (N,) bool, False where V.z <= 0 or the walk would exceed max_cells
    cells: np.ndarray  # (N,) int64, number of cells visited (diagnostic; 0 where invalid)


def real_array(a, name: str) -> np.ndarray:
    """``a`` as a float64 array when it holds real numbers (an integer or floating dtype); an InputError naming
    ``name`` otherwise: complex numbers would lose their imaginary part and strings would be parsed, silently."""
    arr = np.asarray(a)
    if arr.dtype.kind not in "iuf":
        raise InputError(f"{name} has dtype {arr.dtype}; expected real numbers (an integer or floating array)")
    return arr.astype(np.float64, copy=False)


def real_number(x, name: str) -> float:
    """``x`` as a float when it is one real number (int, float or a numpy real scalar, not a bool); an InputError
    naming ``name`` otherwise."""
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        raise InputError(f"{name} = {x!r}; expected a real number")
    return float(x)


def _check_depth(depth) -> np.ndarray:
    d = real_array(depth, "depth")
    if d.ndim != 2 or d.size == 0:
        raise InputError(f"depth must be a non-empty 2D array (rows, cols), got shape {d.shape}")
    bad = ~np.isfinite(d)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise InputError(
            f"depth contains {int(bad.sum())} NaN/inf value(s), first at row {row}, col {col}"
        )
    lo, hi = float(d.min()), float(d.max())
    if lo < 0.0 or hi > 1.0:
        raise InputError(f"depth values must lie in [0, 1], got range [{lo:g}, {hi:g}]")
    return d


def _as_rows(a, width: int, name: str) -> np.ndarray:
    """(width,) or (N, width) real numbers -> finite float64 (N, width)."""
    arr = real_array(a, name)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != width:
        raise InputError(f"{name} must have shape ({width},) or (N, {width}), got {np.shape(a)}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name} contains NaN/inf")
    return arr


def _corners(flat: np.ndarray, rows: int, cols: int, cx, cy, address: str):
    """Depth at the four texel centres around cell (cx, cy): c00, c10 (+x), c01 (+y), c11."""
    i0 = wrap_index(cx, cols, address)
    i1 = wrap_index(cx + 1, cols, address)
    j0 = wrap_index(cy, rows, address) * cols
    j1 = wrap_index(cy + 1, rows, address) * cols
    return flat[j0 + i0], flat[j0 + i1], flat[j1 + i0], flat[j1 + i1]


def sample_bilinear(depth, uv, address: str = "repeat") -> np.ndarray:
    """Depth at uv (N, 2) or (2,) -> (N,) float64, with the sampler model of :func:`exact_hit`.

    Ideal bilinear filtering between texel centres (no 8-bit weight quantisation as real GPUs
    have), REPEAT or CLAMP (clamp-to-edge) addressing (``wgpuviewer.core.sampling.bilinear``).
    ``depth`` is validated like in :func:`exact_hit` (finite, in [0, 1]).
    """
    return bilinear(_check_depth(depth), _as_rows(uv, 2, "uv"), address)


def _first_root(a, b, c, length):
    """Smallest s in [0, length] with a s^2 + b s + c = 0, given c < 0; NaN where none.

    Uses the cancellation-free pair q / a, c / q; a == 0 (linear) falls out of it as -c / b, and
    a == b == 0 (constant, negative) yields no root.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        disc = b * b - 4.0 * a * c
        root_disc = np.sqrt(np.where(disc >= 0.0, disc, np.nan))
        q = -0.5 * (b + np.copysign(root_disc, b))
        best = np.full(a.shape, np.inf)
        for r in (q / a, c / q):
            ok = (r >= -_ROOT_SLACK) & (r <= length + _ROOT_SLACK)  # False for NaN
            best = np.where(ok, np.minimum(best, r), best)
    return np.where(np.isfinite(best), np.clip(best, 0.0, length), np.nan)


def cell_root(flat, rows: int, cols: int, cx, cy, x0, y0, ax, ay, t_enter, t_exit, address: str = "repeat"):
    """Smallest s >= 0 with t - D = 0 at t = t_enter + s inside cell (cx, cy) for the rays (x, y)(t) = (x0, y0) +
    t (ax, ay) (texel coordinates) over [t_enter, t_exit]: 0 where the entry point is already on or below the
    surface; NaN where the cell holds no hit. ``flat`` is the depth map raveled (rows, cols)."""
    length = t_exit - t_enter
    # D inside the cell = A + B fx + C fy + E fx fy with local coordinates fx, fy in [0, 1].
    # Expanding around the entry point (s = t - t_enter) rather than t = 0 keeps the
    # constant terms O(1) however far the ray has travelled, so nothing cancels.
    c00, c10, c01, c11 = _corners(flat, rows, cols, cx, cy, address)
    b_x = c10 - c00
    c_y = c01 - c00
    e_xy = c11 - c10 - c01 + c00
    ex = np.clip(x0 + t_enter * ax - cx, 0.0, 1.0)
    ey = np.clip(y0 + t_enter * ay - cy, 0.0, 1.0)
    # f(s) = t - D = qa s^2 + qb s + qc
    qc = t_enter - (c00 + b_x * ex + c_y * ey + e_xy * ex * ey)
    qb = 1.0 - (b_x * ax + c_y * ay + e_xy * (ex * ay + ey * ax))
    qa = -e_xy * ax * ay
    s = np.where(qc >= 0.0, 0.0, _first_root(qa, qb, qc, length))
    # A root that rounding pushed just past the cell end is caught by the next cell's
    # entry test; at t = 1 there is no next cell, and f(1) >= 0 guarantees a hit there.
    return np.where(np.isnan(s) & (t_exit >= 1.0), length, s)


def _check_rays(depth, uv, view_dir, height_scale, address: str, max_cells):
    """:func:`exact_hit`'s inputs checked: (depth, uv (N, 2), view_dir (N, 3), height_scale), the rays broadcast."""
    d = _check_depth(depth)
    check_address(address)
    p = _as_rows(uv, 2, "uv")
    v = _as_rows(view_dir, 3, "view_dir")
    try:
        n = np.broadcast_shapes((len(p),), (len(v),))[0]
    except ValueError:
        raise InputError(f"uv has {len(p)} rows but view_dir has {len(v)}") from None
    scale = real_number(height_scale, "height_scale")
    if not np.isfinite(scale) or scale < 0.0:
        raise InputError(f"height_scale must be finite and >= 0, got {height_scale!r}")
    if not real_number(max_cells, "max_cells") >= 1:
        raise InputError(f"max_cells must be >= 1, got {max_cells!r}")
    return d, np.broadcast_to(p, (n, 2)), np.broadcast_to(v, (n, 3)), scale


def exact_hit(
    depth, uv, view_dir, height_scale, address: str = "repeat", max_cells: int = MAX_CELLS
) -> Hit:
    """Exact first hit of N view rays with the bilinear depth field ``depth`` (rows, cols).

    ``uv`` (N, 2) or (2,) are the entry points on the surface plane, ``view_dir`` (N, 3) or (3,)
    the tangent-space view vectors towards the eye (one of them broadcasts against the other;
    single inputs give N = 1). Only V.xy / V.z matters, so V need not be normalised, but it must
    be finite. ``height_scale`` S >= 0 is the relief depth in UV units; ``address`` is
    ``"repeat"`` or ``"clamp"``.

    Rays with V.z <= 0 (exactly grazing or back-facing) never descend into the relief: they are
    returned with ``valid = False``, NaN ``t`` and ``uv``, and 0 cells; they do not raise.
    NaN/inf or values outside [0, 1] in ``depth``, non-finite ``uv``/``view_dir``, or anything but real numbers
    (complex, strings) raise InputError (a ValueError).

    Cost is one step per cell crossed, about (t* * S * tan(theta)) * (W |cos phi| + H |sin phi|)
    steps: a grazing ray at 89.9 degrees crosses thousands of cells on a 256-texel map. To stay
    bounded as V.z -> 0+ (design: caps are reported, never silent), a ray whose span t in [0, 1]
    crosses more than ``max_cells`` cells (|floor x(1) - floor x(0)| + |same for y| + 1, decided
    before walking, independent of the map) is declined like V.z <= 0: ``valid = False``, NaN.
    """
    d, p, v, scale = _check_rays(depth, uv, view_dir, height_scale, address, max_cells)
    n = len(p)
    rows, cols = d.shape
    flat = d.ravel()
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        uv_step = v[:, :2] / v[:, 2:3] * scale  # uv(t) = uv0 - t * uv_step
        # The ray in texel coordinates: (x, y)(t) = start + t * texel_step.
        start = p * (cols, rows) - 0.5
        texel_step = -uv_step * (cols, rows)
        reach = np.abs(np.floor(start + texel_step) - np.floor(start)).sum(axis=1) + 1
    valid = (v[:, 2] > 0.0) & (reach <= max_cells)  # NaN/inf reach (V.z <= 0) fails too
    t_hit = np.full(n, np.nan)
    uv_hit = np.full((n, 2), np.nan)
    cells = np.zeros(n, dtype=np.int64)

    ray = np.flatnonzero(valid)  # indices of the rays still walking
    uv0, uv_step = p[ray], uv_step[ray]
    x0, y0 = start[ray, 0], start[ray, 1]
    ax, ay = texel_step[ray, 0], texel_step[ray, 1]
    cx = np.floor(x0).astype(np.int64)
    cy = np.floor(y0).astype(np.int64)
    sx = np.where(ax > 0, 1, -1)
    sy = np.where(ay > 0, 1, -1)
    t_enter = np.zeros(len(ray))
    visited = 0  # all rays start together, so the step count is the cell count

    with np.errstate(divide="ignore", invalid="ignore"):
        while ray.size:
            visited += 1
            # Exit t through the next x / y cell boundary, recomputed from the cell index (no
            # accumulated drift over long walks). t = 1 ends every walk: f(1) = 1 - D >= 0.
            tx = np.where(ax != 0, (cx + (sx > 0) - x0) / ax, np.inf)
            ty = np.where(ay != 0, (cy + (sy > 0) - y0) / ay, np.inf)
            t_exit = np.minimum(np.minimum(tx, ty), 1.0)
            s = cell_root(flat, rows, cols, cx, cy, x0, y0, ax, ay, t_enter, t_exit, address)

            done = ~np.isnan(s)
            if done.any():
                t_star = t_enter[done] + s[done]
                out = ray[done]
                t_hit[out] = t_star
                uv_hit[out] = uv0[done] - t_star[:, None] * uv_step[done]
                cells[out] = visited
                keep = ~done
                ray, uv0, uv_step = ray[keep], uv0[keep], uv_step[keep]
                x0, y0, ax, ay, sx, sy = x0[keep], y0[keep], ax[keep], ay[keep], sx[keep], sy[keep]
                cx, cy = cx[keep], cy[keep]
                tx, ty, t_exit = tx[keep], ty[keep], t_exit[keep]

            # Step into the next cell; through a corner both indices move.
            cx = cx + np.where(tx <= t_exit, sx, 0)
            cy = cy + np.where(ty <= t_exit, sy, 0)
            t_enter = t_exit

    return Hit(uv=uv_hit, t=t_hit, valid=valid, cells=cells)


def uv_error_texels(uv_a, uv_b, size_wh) -> np.ndarray:
    """Wrap-aware (periodic) Euclidean distance between uv (N, 2) or (2,) points, in texels.

    ``size_wh`` = (W, H). Each axis difference is reduced to the nearest periodic image, so
    u = 0.999 and u = 0.001 on a 100-wide map are 0.2 texels apart.
    """
    wh = real_array(size_wh, "size_wh")
    delta = (np.atleast_2d(real_array(uv_a, "uv_a")) - np.atleast_2d(real_array(uv_b, "uv_b"))) * wh
    delta -= np.round(delta / wh) * wh
    return np.hypot(delta[:, 0], delta[:, 1])


def view_dir_from_angles(theta_deg, phi_deg) -> np.ndarray:
    """Unit tangent-space V at angle theta from the normal (0 = looking straight down,
    90 = grazing) and azimuth phi: (sin t cos p, sin t sin p, cos t). Broadcasts; shape (..., 3).
    """
    theta = real_array(theta_deg, "theta_deg")
    t, p = np.broadcast_arrays(np.radians(theta), np.radians(real_array(phi_deg, "phi_deg")))
    # cos(radians(90)) is 6e-17, not 0: that would be a valid ray walking ~1e16 cells. Exactly
    # grazing must give V.z == 0 so exact_hit flags it invalid.
    z = np.where(np.mod(theta, 180.0) == 90.0, 0.0, np.cos(t))
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), z], axis=-1)


# --- self-shadowing -------------------------------------------------------------------------------------------

#: A shadow ray's own surface: an occluder nearer to the shaded point than this many texels of travel along the
#: light ray counts as the point itself (its own slope, the search's rounding), not as a shadow. The renderer's
#: WGSL gets it generated (relief.shaders), so both sides test the same definition.
SHADOW_TOLERANCE_TEXELS = 1.0
#: Depth samples the soft shadow estimate takes along the light ray (the GPU's; the reference samples densely).
SOFT_SHADOW_SAMPLES = 16
#: The soft shadow's penumbra: an occluder rising this much above the light ray, as the tangent of its elevation
#: seen from the shaded point, blocks the whole light (a light of about 0.1 rad radius); below it, a linear fade.
SOFT_SHADOW_PENUMBRA = 0.1
#: The reference's soft estimate samples the light ray every this many texels of travel (a dense maximum).
SOFT_REFERENCE_STEP_TEXELS = 0.125


@dataclass
class Shadow:
    """Result of :func:`shadow` for N shaded points."""

    lit: np.ndarray  # (N,) bool: the hard shadow state, True where the light reaches the point
    visibility: np.ndarray  # (N,) float64 soft visibility in [0, 1] (0: fully shadowed)
    occluder_t: np.ndarray  # (N,) float64 layer depth of the light ray's first hit from the top (NaN: not traced)
    tolerance_t: np.ndarray  # (N,) float64 the tolerance SHADOW_TOLERANCE_TEXELS as layer depth on this ray
    valid: np.ndarray  # (N,) bool: False where the light ray is too long to walk (grazing light, see exact_hit)


def shadow_span(light_dir, height_scale: float, size_wh) -> tuple[np.ndarray, np.ndarray]:
    """UV travel per unit of layer depth along the light rays (N, 2) and the tolerance as layer depth (N,): one
    SHADOW_TOLERANCE_TEXELS of travel, infinite for a vertical light (nothing in a height field shadows it)."""
    light = _as_rows(light_dir, 3, "light_dir")
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        span = light[:, :2] / light[:, 2:3] * height_scale
        texels = np.hypot(span[:, 0] * size_wh[0], span[:, 1] * size_wh[1])
        tolerance = np.where(texels > 0.0, SHADOW_TOLERANCE_TEXELS / texels, np.inf)
    return span, tolerance


def shadow(depth, uv, t, light_dir, height_scale, address: str = "repeat", max_cells: int = MAX_CELLS) -> Shadow:
    """Self-shadowing of N points on (or in) the relief, in float64: point i at ``uv[i]`` (N, 2), layer depth
    ``t[i]`` (N,), lit by a directional light ``light_dir`` (N, 3) or (3,) in tangent space (towards the light).

    Hard: the light ray enters the relief's top at ``uv + t * L.xy / L.z * S`` and descends towards the point; its
    exact first hit (:func:`exact_hit`) is the point itself when the light reaches it. The point is lit iff that hit
    lies at most SHADOW_TOLERANCE_TEXELS of travel before it (``occluder_t >= t - tolerance_t``). A light at or
    below the horizon (L.z <= 0) shadows the point; a point within the tolerance of the top is lit.

    Soft, from the surface point at ``uv`` (t0 = D(uv), whatever ``t`` says: a search stopping a little below the
    surface would otherwise see the relief rise right above it): visibility = clamp(1 - max_s (t_s - D(uv_s)) /
    ((t0 - t_s) tan theta_L) / SOFT_SHADOW_PENUMBRA, 0, 1) over the light ray's points s from the tolerance to the
    top (t_s in [0, t0 - tolerance_t], uv_s where the ray is at layer depth t_s; tan theta_L = |L.xy| / L.z): the
    largest elevation at which the relief rises above the light ray, as seen from the point (Tatarchuk's penumbra
    estimate, normalised per unit distance). The reference takes the maximum over points every
    SOFT_REFERENCE_STEP_TEXELS of travel; the GPU over SOFT_SHADOW_SAMPLES of them.
    """
    d = _check_depth(depth)
    check_address(address)
    p = _as_rows(uv, 2, "uv")
    light = _as_rows(light_dir, 3, "light_dir")
    depth_t = real_array(t, "t").reshape(-1)
    if not np.isfinite(depth_t).all():
        raise InputError("t contains NaN/inf")
    n = max(len(p), len(light), len(depth_t))
    try:
        p, light = np.broadcast_to(p, (n, 2)), np.broadcast_to(light, (n, 3))
        depth_t = np.broadcast_to(depth_t, (n,))
    except ValueError:
        raise InputError(f"uv has {len(p)} rows, t {len(depth_t)} and light_dir {len(light)}; expected equal "
                         "counts, or one for all") from None
    scale = real_number(height_scale, "height_scale")
    if not np.isfinite(scale) or scale < 0.0:
        raise InputError(f"height_scale must be finite and >= 0, got {height_scale!r}")
    rows, cols = d.shape
    span, tolerance = shadow_span(light, scale, (cols, rows))
    above = light[:, 2] > 0.0
    near_top = above & (depth_t <= tolerance)  # no room for an occluder: lit
    traced = above & ~near_top
    lit = near_top.copy()
    surface_t = bilinear(d, p, address)
    visibility = (above & (surface_t <= tolerance)).astype(np.float64)
    occluder_t = np.full(n, np.nan)
    valid = np.ones(n, bool)
    idx = np.flatnonzero(traced)
    if idx.size:
        entry = p[idx] + depth_t[idx, None] * span[idx]
        hit = exact_hit(d, entry, light[idx], scale, address, max_cells)
        occluder_t[idx] = hit.t
        valid[idx] = hit.valid
        lit[idx] = hit.valid & (hit.t >= depth_t[idx] - tolerance[idx])
    walkable = np.ones(n, bool)  # a light ray too long to walk gets no soft estimate either: shadowed
    walkable[idx] = valid[idx]
    soft = np.flatnonzero(above & (surface_t > tolerance) & walkable)
    if soft.size:
        visibility[soft] = _soft_visibility(d, p[soft], surface_t[soft], light[soft], span[soft], tolerance[soft],
                                            address)
    return Shadow(lit=lit, visibility=visibility, occluder_t=occluder_t, tolerance_t=tolerance, valid=valid)


def _soft_visibility(d, uv, t, light, span, tolerance, address: str) -> np.ndarray:
    """The soft visibility of :func:`shadow` for traced points (t > tolerance, L.z > 0), sampled densely."""
    rows, cols = d.shape
    reach = t - tolerance  # layer depth from the top to the nearest sample
    texels = SHADOW_TOLERANCE_TEXELS / tolerance  # texels of travel per unit layer depth
    steps = np.maximum(np.ceil(reach * texels / SOFT_REFERENCE_STEP_TEXELS), 1).astype(np.int64)
    tan_light = np.hypot(light[:, 0], light[:, 1]) / light[:, 2]
    worst = np.zeros(len(t))
    # Rays are walked together, each over its own number of steps: fraction k / steps of its reach, k = 0..steps.
    for k in range(int(steps.max()) + 1):
        frac = np.minimum(k / steps, 1.0)
        t_s = reach * (1.0 - frac)  # from the nearest sample (k = 0) up to the top
        uv_s = uv + (t - t_s)[:, None] * span
        rise = (t_s - bilinear(d, uv_s, address)) / ((t - t_s) * tan_light)
        worst = np.maximum(worst, rise)
    return np.clip(1.0 - worst / SOFT_SHADOW_PENUMBRA, 0.0, 1.0)
