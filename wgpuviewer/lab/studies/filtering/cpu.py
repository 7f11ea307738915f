"""Float64 twins of the texture filters (``wgsl/filters/``, ``wgsl/common/ellipse.wgsl``, ``common/ewa.wgsl``) and
of the visibility test (``wgsl/visibility/traced.wgsl``), for the tests that hold the GPU to them.

Everything follows the WGSL step by step (same level choice, texel cap, walk order, row-ends method, hidden texels'
weights dropped or inherited by their substitutes, fallbacks), in float64, on the float16-rounded mip chain the GPU
holds (``relief.filter_probe.texture_levels``). The visibility test uses the float64 exact hit
(``relief.reference.exact_hit``) where the GPU uses the technique's own trace.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from wgpuviewer.core.sampling import bilinear, nearest
from wgpuviewer.relief.filters import FLAGS, VIS_TOLERANCE, get_filter, resolve_filter_params
from wgpuviewer.relief.reference import exact_hit


def ellipse_coefficients(dx, dy) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Heckbert's A, B, C, F of the ellipse A U^2 + B U V + C V^2 = F, the image of the unit pixel circle under the
    Jacobian with columns ``dx``, ``dy`` (texels per pixel; (..., 2) arrays)."""
    dx, dy = np.asarray(dx, np.float64), np.asarray(dy, np.float64)
    ux, vx, uy, vy = dx[..., 0], dx[..., 1], dy[..., 0], dy[..., 1]
    return vx**2 + vy**2, -2.0 * (ux * vx + uy * vy), ux**2 + uy**2, (ux * vy - uy * vx) ** 2


def footprint_axes(dx, dy) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Semi-axes (major, minor: the Jacobian's singular values) and the unit major direction (..., 2)."""
    a, b, c, _ = ellipse_coefficients(dx, dy)
    p, q, r = c, a, -0.5 * b
    mean = 0.5 * (p + q)
    spread = np.sqrt(0.25 * (p - q) ** 2 + r * r)
    big, small = mean + spread, np.maximum(mean - spread, 0.0)
    d1 = np.stack([r, big - p], -1)
    d2 = np.stack([big - q, r], -1)
    d = np.where((np.sum(d1 * d1, -1) >= np.sum(d2 * d2, -1))[..., None], d1, d2)
    n = np.linalg.norm(d, axis=-1)
    ok = n > 1e-30 * np.maximum(big, 1e-30)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.where(ok[..., None], d / np.where(ok, n, 1.0)[..., None], [1.0, 0.0])
    return np.sqrt(big), np.sqrt(small), unit


@dataclass
class Filtered:
    value: np.ndarray  # (4,) float64
    texels: int = 0
    hidden: int = 0
    flags: int = 0
    #: level -> texel (i, j) -> weight given (EWA family; 0 for texels found hidden; untested ones are absent)
    weights: dict | None = None
    #: level -> substitute texel (i, j) -> weight it inherited from hidden texels (visibility filters, inherit 1)
    substitutes: dict | None = None


def _sanitized(uv, dx, dy, flags: list[int]):
    uv, dx, dy = (np.asarray(a, np.float64) for a in (uv, dx, dy))
    if not np.isfinite(uv).all():
        uv = np.zeros(2)
        flags[0] |= FLAGS["nonfinite"]
    if not (np.isfinite(dx).all() and np.isfinite(dy).all()):
        dx, dy = np.zeros(2), np.zeros(2)
        flags[0] |= FLAGS["nonfinite"]
    return uv, dx, dy


def _texture_bounded(d, size, flags: list[int]):
    texels = np.linalg.norm(d * size)
    limit = max(size)
    if texels > limit:
        flags[0] |= FLAGS["huge"]
        return d * (limit / texels)
    return d


def _size(level: np.ndarray) -> np.ndarray:
    return np.array([level.shape[1], level.shape[0]], np.float64)


def _sample(levels, uv, lod: float) -> np.ndarray:
    """textureSampleLevel with a linear-mipmap sampler: bilinear at two levels, blended (lod clamped)."""
    lod = float(np.clip(lod, 0.0, len(levels) - 1))
    lo = int(np.floor(lod))
    value = bilinear(levels[lo], uv[None])[0]
    if lod > lo:
        value = value + (lod - lo) * (bilinear(levels[lo + 1], uv[None])[0] - value)
    return value


def trilinear(levels, uv, dx, dy) -> Filtered:
    """The ideal trilinear lookup: level log2 of the longer derivative (texels), two bilinear levels blended."""
    flags = [0]
    uv, dx, dy = _sanitized(uv, dx, dy, flags)
    size = _size(levels[0])
    longest = max(np.linalg.norm(dx * size), np.linalg.norm(dy * size), 1e-30)
    return Filtered(_sample(levels, uv, np.log2(longest)), 8, 0, flags[0])


def level0(levels, uv, linear: bool) -> Filtered:
    """nearest (linear False) and bilinear at level 0."""
    flags = [0]
    uv, _, _ = _sanitized(uv, np.zeros(2), np.zeros(2), flags)
    sample = bilinear if linear else nearest
    return Filtered(sample(levels[0], uv[None])[0], 4 if linear else 1, 0, flags[0])


def ewa_approx(levels, uv, dx, dy, max_probes: int = 8, alpha: float = 2.0) -> Filtered:
    flags = [0]
    uv, dx, dy = _sanitized(uv, dx, dy, flags)
    size = _size(levels[0])
    dx, dy = _texture_bounded(dx, size, flags), _texture_bounded(dy, size, flags)
    major, minor, direction = (np.asarray(a) for a in footprint_axes(dx * size, dy * size))
    n = float(np.clip(np.ceil(major / max(minor, 1e-8)), 1.0, max_probes))
    lod = np.log2(max(max(minor, major / n), 1e-8))
    semi = direction * major / size
    value, weight = np.zeros(4), 0.0
    for k in range(int(n)):
        s = (2.0 * k + 1.0 - n) / n
        w = np.exp(-alpha * s * s) - np.exp(-alpha)
        value += w * _sample(levels, uv + s * semi, lod)
        weight += w
    return Filtered(value / weight, 8 * int(n), 0, flags[0])


@dataclass
class _Level:
    level: int
    size: np.ndarray  # (W, H) of the level
    centre: np.ndarray
    a: float
    b: float
    c: float
    half: np.ndarray
    area: float

    @property
    def estimate(self) -> float:
        return self.area + 2.0 * (self.half[0] + self.half[1]) + 1.0

    def rows(self):
        """(j, i0, i1) of each row the ellipse Q < 1 crosses, in the WGSL's order."""
        cx, cy = self.centre
        for j in range(int(np.ceil(cy - self.half[1])), int(np.floor(cy + self.half[1])) + 1):
            y = j - cy
            disc = self.b * self.b * y * y - 4.0 * self.a * (self.c * y * y - 1.0)
            if disc <= 0.0:
                continue
            root = np.sqrt(disc)
            yield (j, int(np.ceil(cx + (-self.b * y - root) / (2.0 * self.a))),
                   int(np.floor(cx + (-self.b * y + root) / (2.0 * self.a))))

    def q(self, i: int, j: int) -> float:
        du, dv = i - self.centre[0], j - self.centre[1]
        return self.a * du * du + self.b * du * dv + self.c * dv * dv

    def texel_uv(self, i: int, j: int) -> np.ndarray:
        return (np.array([i, j], np.float64) + 0.5) / self.size


def _ewa_level(levels, uv, dx, dy, level: int, alpha: float) -> _Level:
    size = _size(levels[level])
    a0, b, c0, _ = ellipse_coefficients(dx * size, dy * size)
    a, c = float(a0) + alpha / 3.0, float(c0) + alpha / 3.0
    f = a * c - 0.25 * float(b) ** 2
    return _Level(level, size, uv * size - 0.5, a / f, float(b) / f, c / f, np.sqrt([c, a]), np.pi * np.sqrt(f))


#: hidden(uv (M, 2)) -> Visibility of those texel centres: which the relief hides from the pixel, and where their
#: rays meet it.
HiddenTest = Callable[[np.ndarray], "Visibility"]


def ewa(levels, uv, dx, dy, *, max_texels: int = 256, alpha: float = 2.0, hidden: HiddenTest | None = None,
        rows: bool = False, inherit: bool = False) -> Filtered:
    """EWA as wgsl/common/ewa.wgsl computes it; ``hidden`` makes it ewa_vis (ewa_vis_rows with ``rows``), whose
    hidden texels' weights are dropped or, with ``inherit``, passed to their substitutes outside the ellipse."""
    flags = [0]
    uv, dx, dy = _sanitized(uv, dx, dy, flags)
    size0 = _size(levels[0])
    dx, dy = _texture_bounded(dx, size0, flags), _texture_bounded(dy, size0, flags)
    _, minor, _ = footprint_axes(dx * size0, dy * size0)
    top = len(levels) - 1
    lod = float(np.clip(np.log2(max(float(minor), 1e-8)) - 1.0, 0.0, top))
    level = int(np.floor(lod))
    frac = lod - level
    for _ in range(32):
        if level >= top:
            break
        estimate = _ewa_level(levels, uv, dx, dy, level, alpha).estimate
        if frac > 0.0:
            estimate += _ewa_level(levels, uv, dx, dy, level + 1, alpha).estimate
        if estimate <= max_texels:
            break
        level, frac = level + 1, 0.0
        flags[0] |= FLAGS["capped"]
    state = {"visited": 0, "texels": 0, "hidden": 0, "weights": {}, "substitutes": {}}
    walk = {"budget": max_texels, "alpha": alpha, "hidden": hidden, "rows": rows, "inherit": inherit}
    value = _ewa_average(levels, uv, _ewa_level(levels, uv, dx, dy, level, alpha), state, flags, **walk)
    if frac > 0.0 and level < top:
        other = _ewa_average(levels, uv, _ewa_level(levels, uv, dx, dy, level + 1, alpha), state, flags, **walk)
        value = value + frac * (other - value)
    return Filtered(value, state["texels"], state["hidden"], flags[0], state["weights"], state["substitutes"])


def substitute_texel(e: _Level, occluder) -> tuple[int, int]:
    """The texel of level ``e`` whose cell holds the uv ``occluder`` (where a hidden texel's ray meets the relief)."""
    i, j = np.floor(np.asarray(occluder, np.float64) * e.size)
    return int(i), int(j)


def _ewa_average(levels, uv, e: _Level, state, flags, *, budget: int, alpha: float, hidden, rows: bool,
                 inherit: bool) -> np.ndarray:
    texture = levels[e.level]
    h, w = texture.shape[:2]
    inside = [(i, j) for j, i0, i1 in e.rows() for i in range(i0, i1 + 1) if e.q(i, j) < 1.0]
    is_hidden, occluders = {}, {}
    if hidden is not None and inside:
        seen = hidden(np.array([e.texel_uv(i, j) for i, j in inside]))
        is_hidden = dict(zip(inside, np.asarray(seen.hidden, bool)))
        occluders = dict(zip(inside, seen.hit))
    acc, weight = np.zeros(texture.shape[2]), 0.0
    weights = state["weights"].setdefault(e.level, {})
    substitutes = state["substitutes"].setdefault(e.level, {})

    def substitute(occluder, wt: float) -> None:
        """wgsl/common/ewa.wgsl's ewa_substitute: the weight goes to the texel whose cell holds the occluder,
        unless that texel lies inside the ellipse (the walk counts or drops it)."""
        nonlocal acc, weight
        i, j = substitute_texel(e, occluder)
        if e.q(i, j) < 1.0:
            return
        acc = acc + wt * texture[j % h, i % w]
        weight += wt
        substitutes[(i, j)] = substitutes.get((i, j), 0.0) + wt
        state["texels"] += 1

    def take(i: int, j: int) -> bool:
        nonlocal acc, weight
        q = e.q(i, j)
        if q >= 1.0:
            return False
        state["visited"] += 1
        wt = np.exp(-alpha * q) - np.exp(-alpha)
        if is_hidden.get((i, j), False):
            state["hidden"] += 1
            weights[(i, j)] = weights.get((i, j), 0.0)
            if inherit:
                substitute(occluders[(i, j)], wt)
            return True
        acc = acc + wt * texture[j % h, i % w]
        weight += wt
        weights[(i, j)] = weights.get((i, j), 0.0) + wt
        state["texels"] += 1
        return False

    def full() -> bool:
        if state["visited"] >= budget:
            flags[0] |= FLAGS["capped"]
            return True
        return False

    def result() -> np.ndarray:
        return bilinear(texture, uv[None])[0] if weight <= 0.0 else acc / weight

    for j, i0, i1 in e.rows():
        stop = i1 + 1
        for i in range(i0, i1 + 1):
            if full():
                return result()
            if take(i, j) and rows:
                stop = i
                break
        if rows and stop <= i1:
            back = i1
            while back > stop:
                if full():
                    return result()
                if take(back, j):
                    break
                back -= 1
            state["hidden"] += max(back - stop - 1, 0)
    return result()


@dataclass
class Visibility:
    """The float64 visibility of texel centres seen along one view direction."""

    hidden: np.ndarray  # (M,) bool: the ray towards the texel meets the relief more than VIS_TOLERANCE before it
    margin: np.ndarray  # (M,) float64: D(uv) - t* (layer depth the ray is short of the texel; ~0 when visible)
    hit: np.ndarray  # (M, 2) float64: where that ray first meets the relief (not wrapped; NaN where declined)


def texel_visibility(depth: np.ndarray, uv: np.ndarray, view_dir, height_scale: float) -> Visibility:
    """wgsl/visibility/traced.wgsl in float64: the ray reaching (uv, D(uv)) enters at uv + D P; hidden when its
    exact first hit t* < D - VIS_TOLERANCE; that hit is the hidden texel's occluder."""
    from wgpuviewer.relief.reference import sample_bilinear

    uv = np.atleast_2d(np.asarray(uv, np.float64))
    v = np.asarray(view_dir, np.float64)
    d = sample_bilinear(depth, uv)
    span = v[:2] / max(v[2], 1e-4) * height_scale
    hit = exact_hit(depth, uv + d[:, None] * span, v, height_scale)
    margin = np.where(hit.valid, d - hit.t, 0.0)
    return Visibility(margin > VIS_TOLERANCE, margin, hit.uv)


def hidden_test(depth: np.ndarray, view_dir, height_scale: float) -> HiddenTest:
    """The visibility filters' test of texel centres on ``depth`` seen along ``view_dir`` (texel_visibility)."""
    return lambda uv: texel_visibility(depth, uv, view_dir, height_scale)


def cpu_filter(name: str, levels, uv, dx, dy, *, params: dict | None = None, hidden: HiddenTest | None = None) -> Filtered:
    """The float64 twin of filter ``name`` (aniso: no twin exists, the driver decides; None is returned)."""
    f = get_filter(name)
    p = resolve_filter_params(f, params)
    if name in ("nearest", "bilinear"):
        return level0(levels, uv, name == "bilinear")
    if name == "trilinear":
        return trilinear(levels, uv, dx, dy)
    if name == "ewa_approx":
        return ewa_approx(levels, uv, dx, dy, p["max_probes"], p["alpha"])
    if f.texel_loop:
        return ewa(levels, uv, dx, dy, max_texels=p["max_texels"], alpha=p["alpha"],
                   hidden=hidden if f.visibility else None, rows=name == "ewa_vis_rows",
                   inherit=bool(p.get("inherit", 0)))
    return None
