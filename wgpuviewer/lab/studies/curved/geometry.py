"""The relief on a curved base surface, in float64: the exact first hit of a straight view ray with a height field
displaced inward along the normal of a sphere or a cylinder of radius R, and the same ray traced in the tangent
plane at its entry point (what every relief technique computes: ``relief.reference.exact_hit``).

Frame and units: the entry point is the origin, the outward normal there +z, the tangent frame x = u, y = v (the
project's tangent space); lengths are UV units (one texture tile = 1), so the height scale S, the radius R and the
uv offsets share one unit and a texel is 1/W by 1/H of it. The base surface's centre (sphere) or axis (cylinder,
along v: curved along u only) lies at z = -R.

The texture chart is isometric at the entry point, so a flat surface (R = inf) gives the tangent-plane trace exactly:
- sphere: geodesic normal coordinates around the entry point (the azimuthal equidistant projection): a point whose
  radial projection onto the shell lies at arc length s from the entry, in the tangent direction e, has
  uv = uv0 + s e;
- cylinder: the cylinder unrolled (an isometry): u = u0 + R * (angle about the axis), v = v0 + (distance along it).
A point at distance rho from the centre (axis) lies R - rho below the shell: layer depth t = (R - rho) / S, the
renderer's convention (t = 0 at the top, t = 1 at the deepest relief, depth map D = 1 - H).

The curved hit is the smallest ray length tau with t(tau) >= D(uv(tau)): the ray is sampled at steps of at most
MARCH_TEXELS of uv travel and MARCH_LAYERS of layer depth; the first sample on or below the relief brackets the hit,
and an interval above the relief that a Lipschitz bound says may still hold a root is searched finer first (see
:func:`curved_hit`); BISECTIONS halvings finish it (far below 1e-9 in tau). A ray on a convex surface can leave the
shell again without reaching the relief (the silhouette): it is a *miss*, reported apart from the hits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wgpuviewer.core.sampling import bilinear
from wgpuviewer.relief.reference import exact_hit, uv_error_texels

SURFACES = ("sphere", "cylinder")
#: The march's step bounds: uv travel in texels and layer depth per sample.
MARCH_TEXELS = 1.0 / 16.0
MARCH_LAYERS = 1.0 / 64.0
#: Halvings of the bracket (its width shrinks 2^-60: far below 1e-9 of any step).
BISECTIONS = 60
#: Top-level samples one ray may take; a longer ray is flagged capped (reported, never silent).
MAX_SAMPLES = 200_000
#: Samples evaluated at once per ray at the top level (memory: rays x CHUNK values).
CHUNK = 256
#: A suspicious interval is searched at this many times finer samples, at most LEVELS - 1 times nested.
SUBDIVISION = 16
LEVELS = 9


@dataclass(frozen=True)
class Surface:
    kind: str  # "sphere" or "cylinder" (curved along u)
    radius: float  # R in UV units; math.inf: the tangent plane itself

    def __post_init__(self):
        if self.kind not in SURFACES:
            raise ValueError(f"surface {self.kind!r}: expected one of {', '.join(SURFACES)}")
        if not self.radius > 0:
            raise ValueError(f"radius {self.radius!r}: expected > 0")

    def locate(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points ``p`` (..., 3) in the entry frame -> (uv offset from the entry (..., 2), depth below the shell
        (...,)), both in UV units."""
        x, y, z = p[..., 0], p[..., 1], p[..., 2]
        r = self.radius
        if math.isinf(r):
            return np.stack([x, y], axis=-1), -z
        if self.kind == "sphere":
            h = np.hypot(x, y)
            rho = np.sqrt(h * h + (z + r) ** 2)
            # R - rho without cancellation (rho ~ R for large R): (R^2 - rho^2) / (R + rho).
            depth = -(h * h + z * z + 2.0 * z * r) / (r + rho)
            arc = r * np.arctan2(h, z + r)
            with np.errstate(invalid="ignore", divide="ignore"):
                scale = np.where(h > 0.0, arc / h, 1.0)
            return np.stack([x * scale, y * scale], axis=-1), depth
        rho = np.hypot(x, z + r)
        depth = -(x * x + z * z + 2.0 * z * r) / (r + rho)
        return np.stack([r * np.arctan2(x, z + r), y], axis=-1), depth

    def ray_end(self, down: np.ndarray, height_scale: float) -> np.ndarray:
        """For rays from the entry along unit ``down`` (N, 3) (= -V): the ray length (N,) where it reaches the
        relief's floor (depth S), or else where it leaves the shell again."""
        vz = -down[:, 2]  # V.z > 0
        if math.isinf(self.radius):
            return height_scale / vz
        r, s = self.radius, height_scale
        # |q(tau)|^2 = a tau^2 - 2 b tau + R^2 with q the part of (p + R z) the surface curves in.
        a = 1.0 if self.kind == "sphere" else down[:, 0] ** 2 + down[:, 2] ** 2
        b = r * vz
        c = s * (2.0 * r - s)  # R^2 - (R - S)^2
        disc = b * b - a * c
        floor = disc >= 0.0
        with np.errstate(invalid="ignore"):
            deep = c / (b + np.sqrt(np.where(floor, disc, 0.0)))  # the small root, without cancellation
        return np.where(floor, deep, 2.0 * b / a)


@dataclass
class CurvedHit:
    """Result of :func:`curved_hit` for N rays."""

    uv: np.ndarray  # (N, 2) hit uv (not wrapped; NaN where the ray misses or is capped)
    t: np.ndarray  # (N,) layer depth of the hit below the shell (NaN likewise)
    hit: np.ndarray  # (N,) bool
    miss: np.ndarray  # (N,) bool: the ray left the shell without touching the relief (silhouette)
    capped: np.ndarray  # (N,) bool: longer than MAX_SAMPLES top-level samples, not traced


def lipschitz(depth: np.ndarray, surface: Surface, height_scale: float) -> float:
    """A bound on |d(t - D)/d tau| along any ray inside the shell: the layer depth changes at most 1/S per unit of
    ray (depth changes no faster than the ray moves), the uv at most ``stretch`` per unit, and the bilinear D at most
    by its steepest neighbour difference per texel (repeat addressing) in each axis."""
    rows, cols = depth.shape
    gx = np.abs(np.roll(depth, -1, axis=1) - depth).max() * cols
    gy = np.abs(np.roll(depth, -1, axis=0) - depth).max() * rows
    return 1.0 / height_scale + _stretch(surface, height_scale) * math.hypot(gx, gy)


def _stretch(surface: Surface, height_scale: float) -> float:
    """The most uv travel per unit of ray inside the shell: R / (R - S) (1 on the plane)."""
    return 1.0 if math.isinf(surface.radius) else surface.radius / max(surface.radius - height_scale, 1e-300)


def march_step(surface: Surface, size_wh: tuple[int, int], height_scale: float) -> float:
    """Ray length per sample: at most MARCH_TEXELS of uv travel and MARCH_LAYERS of layer depth."""
    return min(MARCH_TEXELS / (max(size_wh) * _stretch(surface, height_scale)), MARCH_LAYERS * height_scale)


def curved_hit(depth: np.ndarray, surface: Surface, uv0: np.ndarray, view: np.ndarray, height_scale: float,
               address: str = "repeat") -> CurvedHit:
    """The first hit of rays entering at ``uv0`` (N, 2) with unit view vectors ``view`` (N, 3) (towards the eye,
    V.z > 0) with the bilinear ``depth`` (rows, cols) displaced inward by ``height_scale`` on ``surface``.

    The march samples f = t - D; an interval between two samples above the relief (f < 0) can still hold a root
    when the Lipschitz bound allows f to reach 0 between them (f_a + f_b + L width >= 0): such an interval is
    searched at SUBDIVISION times finer samples, recursively (at most LEVELS - 1 times nested), before the march
    goes on. So no feature is stepped over unless it reaches into the ray by less than L times the finest
    width (~1e-11 layers): that is a tangency, taken as a hit."""
    rows, cols = depth.shape
    n = len(uv0)
    down = -np.asarray(view, np.float64)
    end = surface.ray_end(down, height_scale)
    step = march_step(surface, (cols, rows), height_scale)
    bound = lipschitz(depth, surface, height_scale)
    capped = np.ceil(end / step) + 1 > MAX_SAMPLES
    out = CurvedHit(np.full((n, 2), np.nan), np.full(n, np.nan), np.zeros(n, bool), np.zeros(n, bool), capped)

    def f(idx, tau):
        """t - D at ray lengths ``tau`` (len(idx), m) of rays ``idx``; with the uv and the depths below the shell."""
        offset, below = surface.locate(tau[..., None] * down[idx, None, :])
        uv = uv0[idx, None, :] + offset
        d = bilinear(depth, uv.reshape(-1, 2), address).reshape(tau.shape)
        value = below / height_scale - d
        # At the floor (t >= 1 >= D) the ray is in the relief, whatever rounding says.
        return np.where(below >= height_scale * (1.0 - 1e-12), np.maximum(value, 0.0), value), uv, below

    lo = np.zeros(n)
    hi = np.zeros(n)
    active = np.flatnonzero(~capped)
    first = 0
    while active.size:
        k = np.arange(first, first + CHUNK + 1)
        tau = np.minimum(k[None, :] * step, end[active, None])
        value = f(active, tau)[0]
        ray, a, b = _first_brackets(active, tau, value, bound, f, entry=first == 0)
        lo[ray], hi[ray] = a, b
        out.hit[ray] = True
        left = ~out.hit[active]
        out.miss[active[left & (tau[:, -1] >= end[active])]] = True
        active = active[left & (tau[:, -1] < end[active])]
        first += CHUNK

    idx = np.flatnonzero(out.hit)
    a, b = lo[idx], hi[idx]
    entry = b == 0.0  # on the relief at the entry point itself
    for _ in range(BISECTIONS):
        mid = 0.5 * (a + b)
        below_relief = f(idx, mid[:, None])[0][:, 0] >= 0.0
        b = np.where(below_relief, mid, b)
        a = np.where(below_relief, a, mid)
    b = np.where(entry, 0.0, b)
    _, uv, below = f(idx, b[:, None])
    out.uv[idx] = uv[:, 0]
    out.t[idx] = below[:, 0] / height_scale
    return out


def _first_brackets(idx, tau, value, bound, f, entry: bool):
    """The first interval of each ray's samples ``tau`` (values ``value``) that holds a root: (rays, lo, hi) for the
    rays that have one. Every interval before a ray's first sign change that may hold a root by the Lipschitz bound
    is searched at SUBDIVISION times finer samples, breadth first (all such intervals of all rays at once, a level
    at a time); the earliest bracket found wins. ``entry``: the first sample is the entry point."""
    below = value >= 0.0
    bracket = ~below[:, :-1] & below[:, 1:]
    if entry:  # on the relief at the entry point itself: a bracket of width 0
        bracket[:, 0] |= below[:, 0]
    rows = np.arange(len(idx))
    has = bracket.any(axis=1)
    j = np.where(has, np.argmax(bracket, axis=1), bracket.shape[1])
    at_entry = has & (j == 0) & below[:, 0] if entry else np.zeros(len(idx), bool)
    found_ray = [idx[has]]
    found_lo = [np.where(at_entry[has], tau[has, 0], tau[rows[has], j[has]])]
    found_hi = [np.where(at_entry[has], tau[has, 0], tau[rows[has], np.minimum(j[has] + 1, tau.shape[1] - 1)])]
    before = np.arange(bracket.shape[1])[None, :] < j[:, None]
    maybe = _maybe(value, tau, bound) & before
    pair, col = np.nonzero(maybe)
    ray, a, b = idx[pair], tau[pair, col], tau[pair, col + 1]
    fractions = np.linspace(0.0, 1.0, SUBDIVISION + 1)
    for level in range(1, LEVELS):
        if not ray.size:
            break
        sub = a[:, None] + (b - a)[:, None] * fractions[None, :]
        sub[:, -1] = b
        v = f(ray, sub)[0]
        below = v >= 0.0
        bracket = ~below[:, :-1] & below[:, 1:]
        maybe = _maybe(v, sub, bound)
        if level == LEVELS - 1:  # a tangency within ~1e-11 layers: taken as a hit
            bracket |= maybe
        has = bracket.any(axis=1)
        j = np.where(has, np.argmax(bracket, axis=1), bracket.shape[1])
        rows = np.flatnonzero(has)
        found_ray.append(ray[rows])
        found_lo.append(sub[rows, j[rows]])
        found_hi.append(sub[rows, j[rows] + 1])
        maybe &= np.arange(bracket.shape[1])[None, :] < j[:, None]
        pair, col = np.nonzero(maybe)
        ray, a, b = ray[pair], sub[pair, col], sub[pair, col + 1]
    ray, lo, hi = np.concatenate(found_ray), np.concatenate(found_lo), np.concatenate(found_hi)
    order = np.lexsort((lo, ray))
    ray, lo, hi = ray[order], lo[order], hi[order]
    first = np.r_[True, ray[1:] != ray[:-1]] if ray.size else np.zeros(0, bool)
    return ray[first], lo[first], hi[first]


def _maybe(value, tau, bound):
    """Intervals between two samples above the relief where f may still reach 0 (f_a + f_b + L width >= 0)."""
    width = tau[:, 1:] - tau[:, :-1]
    return ((value[:, :-1] < 0.0) & (value[:, 1:] < 0.0) & (width > 0)
            & (value[:, :-1] + value[:, 1:] + bound * width >= 0.0))


@dataclass
class Comparison:
    """The tangent-plane trace against the curved truth for N rays."""

    error: np.ndarray  # (N,) texels between the hits (NaN where either has none)
    curved: CurvedHit
    flat_valid: np.ndarray  # (N,) bool: the tangent-plane trace has a hit (False only when capped)


def compare(depth: np.ndarray, surface: Surface, uv0: np.ndarray, view: np.ndarray, height_scale: float,
            flat=None) -> Comparison:
    """Both hits of the rays and their distance in texels (wrap-aware); ``flat``: the tangent-plane hits when
    already traced (they do not depend on the surface)."""
    rows, cols = depth.shape
    flat = flat if flat is not None else exact_hit(depth, uv0, view, height_scale)
    curved = curved_hit(depth, surface, uv0, view, height_scale)
    both = curved.hit & flat.valid
    error = np.full(len(uv0), np.nan)
    if both.any():
        error[both] = uv_error_texels(curved.uv[both], flat.uv[both], (cols, rows))
    return Comparison(error, curved, flat.valid)
