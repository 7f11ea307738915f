"""Probe-against-reference measurements: UV error in texels, fetches per ray, capped fraction, the
divergence-aware SIMD-tile cost, and self-shadowing errors (hard state, soft visibility) against the float64 shadow.

Used by the tests, the accuracy study (``wgpuviewer accuracy``: ``run`` and ``shadow_run``), the benchmark and the
shadows study, so every number about a technique's error and cost is computed one way.
"""

from __future__ import annotations

import math
import numbers
import time
from dataclasses import dataclass

import numpy as np

from wgpuviewer.core.errors import InputError
from wgpuviewer.core.params import resolve_params
from wgpuviewer.techniques import TECHNIQUES, get_technique

from .probe import probe, shadow_probe
from .reference import Hit, exact_hit, real_array, real_number, shadow, uv_error_texels, view_dir_from_angles


@dataclass
class Accuracy:
    technique: str
    angle: float
    params: dict
    error_mean: float  # texels, over rays that were not capped
    error_p95: float
    error_max: float
    fetches_mean: float
    fetches_p95: float
    capped: float  # fraction of rays flagged capped
    rays: int


#: SIMD group shape for the divergence-aware cost: 8 x 4 = 32 lanes (a warp / wave32), screen tiles of pixels.
SIMD_TILE = (8, 4)


def simd_tile_cost(fetches: np.ndarray, tile: tuple[int, int] = SIMD_TILE, covered: np.ndarray | None = None) -> float:
    """Mean over screen tiles (``tile`` = (width, height) pixels) of the *maximum* fetch count in the tile: what a
    SIMD group pays when its lanes run a loop until the slowest one is done. ``fetches`` is (H, W); ``covered``
    (H, W) bool marks the pixels that ran (others count as absent lanes; tiles with none are skipped). Partial
    tiles at the right and bottom borders count with the lanes they have. NaN when no pixel is covered."""
    f = np.asarray(fetches, np.float64)
    if f.ndim != 2:
        raise InputError(f"simd_tile_cost: fetches must be a 2D (H, W) array, got shape {f.shape}")
    tw, th = tile
    if tw < 1 or th < 1:
        raise InputError(f"simd_tile_cost: tile = {tile}: expected positive (width, height)")
    h, w = f.shape
    if covered is not None and not np.all(covered):
        f = np.where(np.asarray(covered, bool), f, -np.inf)
    ph, pw = -h % th, -w % tw
    if ph or pw:
        f = np.pad(f, ((0, ph), (0, pw)), constant_values=-np.inf)
    rows, cols = (h + ph) // th, (w + pw) // tw
    # the tile rows' maxima first, then along each row: the same maxima, several times faster than max(axis=(1, 3))
    peaks = f.reshape(rows, th, cols * tw).max(axis=1).reshape(rows, cols, tw).max(axis=2)
    used = peaks[np.isfinite(peaks)]
    return float(used.mean()) if used.size else float("nan")


#: Most rays one measurement traces: the probe's ray and hit buffers take 32 bytes a ray each, and 2^22 rays fill
#: WebGPU's default 128 MiB storage buffer (the float64 reference needs a few hundred bytes a ray besides).
MAX_RAYS = 1 << 22
#: View angles are degrees from the normal in [0, MAX_ANGLE): at 90 degrees (grazing) no ray descends into the
#: relief, and every error statistic would be NaN.
MAX_ANGLE = 90.0


def check_rays(rays, where: str = "measure") -> int:
    """``rays`` when it is a whole number from 1 to MAX_RAYS; an InputError naming it otherwise."""
    if isinstance(rays, bool) or not isinstance(rays, numbers.Integral):
        raise InputError(f"{where}: rays = {rays!r}; expected a whole number of rays, 1 to {MAX_RAYS}")
    if not 1 <= rays <= MAX_RAYS:
        raise InputError(f"{where}: rays = {rays}; expected 1 to {MAX_RAYS} (32 bytes a ray in the probe's ray and "
                         f"hit buffers, within WebGPU's default 128 MiB storage buffer); measure more seeds instead")
    return int(rays)


def check_angle(angle, where: str = "measure") -> float:
    """``angle`` (degrees from the normal) when it is a real number in [0, MAX_ANGLE); an InputError otherwise."""
    a = real_number(angle, f"{where}: angle_deg")
    if not (math.isfinite(a) and 0.0 <= a < MAX_ANGLE):
        raise InputError(f"{where}: angle_deg = {angle!r}; expected 0 <= angle < {MAX_ANGLE:g} degrees from the "
                         "normal (at 90, grazing, no ray enters the relief)")
    return a


def _checked(where: str, technique: str, params: dict, height, height_scale, rays) -> tuple[np.ndarray, int]:
    """The arguments measure and run share, checked before any tracing: (height as float64, rays)."""
    resolve_params(get_technique(technique), params)
    height = real_array(height, f"{where}: height")
    scale = real_number(height_scale, f"{where}: height_scale")
    if not (math.isfinite(scale) and scale >= 0.0):
        raise InputError(f"{where}: height_scale = {height_scale!r}; expected a finite relief depth >= 0 UV units")
    return height, check_rays(rays, where)


def random_rays(n: int, angle_deg: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``n`` entry points uniform over the texture, view directions at ``angle_deg`` from the normal
    with uniformly random azimuth."""
    rng = np.random.default_rng(seed)
    uv = rng.random((n, 2))
    view = view_dir_from_angles(np.full(n, angle_deg), rng.random(n) * 360.0)
    return uv, view


def measure(
    technique: str, height: np.ndarray, angle_deg: float, height_scale: float = 0.05,
    rays: int = 4096, seed: int = 0, backend: str | None = None, **params,
) -> Accuracy:
    """Trace ``rays`` random rays (1 to MAX_RAYS) at ``angle_deg`` (degrees from the normal, 0 <= angle < 90) with the
    GPU probe and the float64 reference. Arguments it cannot use raise InputError before anything is traced."""
    height, rays = _checked("measure", technique, params, height, height_scale, rays)
    angle_deg = check_angle(angle_deg)
    uv, view = random_rays(rays, angle_deg, seed)
    ref = exact_hit(1.0 - height, uv, view, height_scale)
    return _scored(technique, params, height, angle_deg, uv, view, ref, height_scale, backend)


def _scored(technique: str, params: dict, height: np.ndarray, angle_deg: float, uv, view, ref: Hit,
            height_scale: float, backend) -> Accuracy:
    """The probe's hits for rays (uv, view) against their reference hits ``ref``."""
    got = probe(technique, height, uv, view, height_scale, backend=backend, **params)
    ok = ~got.capped & ref.valid
    err = uv_error_texels(got.uv[ok], ref.uv[ok], height.shape[::-1]) if ok.any() else np.array([np.nan])
    fetches = got.fetches.astype(np.float64)
    return Accuracy(
        technique=technique, angle=angle_deg, params=params,
        error_mean=float(np.mean(err)), error_p95=float(np.percentile(err, 95)), error_max=float(np.max(err)),
        fetches_mean=float(fetches.mean()), fetches_p95=float(np.percentile(fetches, 95)),
        capped=float(got.capped.mean()), rays=len(uv),
    )


DEFAULT_ANGLES = (0.0, 30.0, 45.0, 60.0, 75.0, 80.0, 85.0, 89.0, 89.9)
#: (technique, parameter overrides) ``wgpuviewer accuracy`` measures: each ray-search entry's accuracy_settings.
DEFAULT_SETTINGS: tuple[tuple[str, dict], ...] = tuple(
    (name, params) for name, t in TECHNIQUES.items() if t.ray_search for params in t.accuracy_settings
)


def npot_height(shape=(401, 343)) -> np.ndarray:
    """A smooth non-square, non-power-of-two test relief (rows, cols) = (401, 343) by default."""
    rows, cols = shape
    return np.clip(0.5 + 0.2 * np.sin(np.arange(rows)[:, None] / 9.0) * np.cos(np.arange(cols)[None, :] / 7.0), 0, 1)


@dataclass
class Measured:
    """What every run of measurements records: ``rays`` random rays per case, the ``seconds`` it took, and the
    ``results`` by case (the key is the run's own)."""

    rays: int
    seconds: float
    results: dict


@dataclass
class Run(Measured):
    """One accuracy run: every setting at every angle on every height map, the same random rays (seed 0) for every
    setting of a (map, angle), each traced once by the float64 reference. ``results``: (height map, index in
    settings, angle) -> the Accuracy."""
    heightmaps: dict[str, tuple[int, int]]  # name -> (rows, cols)
    angles: tuple[float, ...]
    settings: tuple[tuple[str, dict], ...]
    height_scale: float


def run(heightmaps: dict, angles=DEFAULT_ANGLES, settings=DEFAULT_SETTINGS, height_scale=0.05, rays=4096,
        backend=None, progress=None) -> Run:
    """Measure each setting at each angle on each height map (``progress()`` after each measurement); arguments are
    checked as ``measure`` checks them, all before anything is traced."""
    angles = tuple(check_angle(angle, "run") for angle in angles)
    maps = {}
    for name, height in heightmaps.items():
        for technique, params in settings:
            maps[name], rays = _checked("run", technique, params, height, height_scale, rays)
    start = time.perf_counter()
    results = {}
    for name, height in maps.items():
        for angle in angles:
            uv, view = random_rays(rays, angle)
            ref = exact_hit(1.0 - height, uv, view, height_scale)
            for i, (technique, params) in enumerate(settings):
                results[name, i, angle] = _scored(technique, params, height, angle, uv, view, ref, height_scale,
                                                  backend)
                if progress:
                    progress()
    return Run(rays=rays, seconds=time.perf_counter() - start, results=results,
               heightmaps={name: np.shape(h) for name, h in heightmaps.items()}, angles=tuple(angles),
               settings=tuple(settings), height_scale=height_scale)


# --- self-shadowing ------------------------------------------------------------------------------------------------

#: Light elevations (degrees above the surface) of the accuracy report's self-shadowing table.
SHADOW_ELEVATIONS = (30.0, 45.0, 60.0, 80.0)
#: The light's tangent-space azimuth (degrees; views of azimuth 0 see it from the side, towards the viewer).
LIGHT_AZIMUTH = 150.0
#: The view angle (degrees from the normal) of the accuracy report's shadow rays.
SHADOW_VIEW_ANGLE = 45.0


def shadowing_techniques() -> list[str]:
    """The techniques whose ``trace`` searches along the ray: ray searches on the depth map with more than one
    fetch (parallax offsets by one fetch: no first hit to shadow from)."""
    return [name for name, t in TECHNIQUES.items()
            if t.ray_search and t.needs_depth and t.fetch_bound(t.defaults()) > 1]


def light_direction(elevation: float, azimuth: float = LIGHT_AZIMUTH) -> np.ndarray:
    """Tangent-space unit direction towards a light ``elevation`` degrees above the surface at tangent-space
    ``azimuth`` degrees."""
    e, a = np.radians(elevation), np.radians(azimuth)
    return np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])


@dataclass
class ShadowAccuracy:
    """One technique's self-shadowing at one light, over the rays with a valid exact hit: the hard state and soft
    visibility cast from the exact hit (the shadow ray's own error) and from the technique's own view hit (what the
    renderer draws: both rays' errors), against ``reference.shadow`` from the exact hit."""

    technique: str
    elevation: float
    rays: int
    ref_lit: float  # fraction of the rays the reference lights
    hard_wrong: float  # fraction with the wrong hard state, at the exact hit
    hard_wrong_own_hit: float  # the same at the technique's own view hit
    soft_diff: float  # mean |visibility - reference|, at the exact hit
    soft_diff_own_hit: float
    hard_fetches: np.ndarray  # (rays,) depth fetches per shadow ray from the exact hit
    soft_fetches: float  # mean depth fetches per soft estimate
    view_fetches: float  # mean depth fetches per view ray
    capped: float  # fraction of shadow rays flagged capped
    lit: np.ndarray  # (rays,) the hard state at the own hit
    ref_lit_rays: np.ndarray  # (rays,) the reference's hard state


def measure_shadows(height: np.ndarray, techniques, elevations, uv, view, height_scale: float,
                    backend: str | None = None, progress=None) -> tuple[np.ndarray, list[ShadowAccuracy]]:
    """Every technique's self-shadowing of the exact first hits of the rays (``uv`` (N, 2), one ``view``) at each
    light elevation; ``progress()`` after each. Returns the rays with a valid exact hit (N,) bool, and the results
    (technique-major within each elevation)."""
    depth = 1.0 - np.asarray(height, np.float64)
    exact = exact_hit(depth, uv, view, height_scale)
    ok = exact.valid
    exact_uv, exact_t = np.mod(exact.uv[ok], 1.0), exact.t[ok]
    hits = {t: probe(t, height, uv[ok], view, height_scale, backend=backend) for t in techniques}
    out = []
    for elevation in elevations:
        direction = light_direction(elevation)
        truth = shadow(depth, exact_uv, exact_t, direction, height_scale)
        for technique in techniques:
            hit = hits[technique]
            at_exact = shadow_probe(technique, height, exact_uv, exact_t, direction, height_scale, backend=backend)
            own = shadow_probe(technique, height, np.mod(hit.uv, 1.0), hit.depth, direction, height_scale,
                               backend=backend)
            out.append(ShadowAccuracy(
                technique, float(elevation), int(ok.sum()), float(truth.lit.mean()),
                float((at_exact.lit != truth.lit).mean()), float((own.lit != truth.lit).mean()),
                float(np.abs(at_exact.visibility - truth.visibility).mean()),
                float(np.abs(own.visibility - truth.visibility).mean()),
                at_exact.hard_fetches.astype(np.float64), float(at_exact.soft_fetches.mean()),
                float(hit.fetches.mean()), float(at_exact.capped.mean()), own.lit, truth.lit))
            if progress:
                progress()
    return ok, out


@dataclass
class ShadowRun(Measured):
    """``shadow_run``'s measurements: ``results``, (height map, technique, elevation) -> ShadowAccuracy."""

    techniques: tuple[str, ...]
    elevations: tuple[float, ...]
    view_angle: float


def shadow_run(heightmaps: dict, techniques=None, elevations=SHADOW_ELEVATIONS, height_scale=0.05, rays=4096,
               backend=None, progress=None) -> ShadowRun:
    """``measure_shadows`` on each height map with ``rays`` random rays at SHADOW_VIEW_ANGLE (the same rays for every
    technique); ``progress()`` after each technique and elevation."""
    techniques = tuple(techniques or shadowing_techniques())
    start = time.perf_counter()
    results = {}
    uv, view = random_rays(rays, SHADOW_VIEW_ANGLE)
    for name, height in heightmaps.items():
        _, measured = measure_shadows(height, techniques, elevations, uv, view, height_scale, backend, progress)
        results.update({(name, m.technique, m.elevation): m for m in measured})
    return ShadowRun(rays=rays, seconds=time.perf_counter() - start, results=results, techniques=techniques,
                     elevations=tuple(elevations), view_angle=SHADOW_VIEW_ANGLE)
