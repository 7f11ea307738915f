"""Probe-against-reference measurements: UV error in texels, fetches per ray, capped fraction, and the
divergence-aware SIMD-tile cost.

Used by the tests, ``wgpuviewer accuracy`` and the benchmark, so every number about a technique's error and cost
is computed one way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wgpuviewer.core.errors import InputError

from .probe import probe
from .reference import exact_hit, uv_error_texels, view_dir_from_angles


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
    """Trace ``rays`` random rays at ``angle_deg`` with the GPU probe and the float64 reference."""
    height = np.asarray(height, np.float64)
    uv, view = random_rays(rays, angle_deg, seed)
    got = probe(technique, height, uv, view, height_scale, backend=backend, **params)
    ref = exact_hit(1.0 - height, uv, view, height_scale)
    ok = ~got.capped & ref.valid
    err = uv_error_texels(got.uv[ok], ref.uv[ok], height.shape[::-1]) if ok.any() else np.array([np.nan])
    fetches = got.fetches.astype(np.float64)
    return Accuracy(
        technique=technique, angle=angle_deg, params=params,
        error_mean=float(np.mean(err)), error_p95=float(np.percentile(err, 95)), error_max=float(np.max(err)),
        fetches_mean=float(fetches.mean()), fetches_p95=float(np.percentile(fetches, 95)),
        capped=float(got.capped.mean()), rays=rays,
    )


DEFAULT_ANGLES = (0.0, 30.0, 45.0, 60.0, 75.0, 80.0, 85.0, 89.0, 89.9)
DEFAULT_SETTINGS = (
    ("parallax", {}), ("parallax", {"offset_limiting": True}),
    ("steep", {"layers": 32}), ("pom", {"layers": 8}), ("pom", {"layers": 32}), ("pom", {"layers": 256}),
    ("pom_adaptive", {}), ("pom_adaptive", {"angle_only": True}),
    ("relief", {}), ("relief", {"linear_steps": 32, "binary_steps": 8}),
    ("maxmip", {}), ("distance", {}), ("distance_refined", {}), ("cone", {}),
)


def npot_height(shape=(401, 343)) -> np.ndarray:
    """A smooth non-square, non-power-of-two test relief (rows, cols) = (401, 343) by default."""
    rows, cols = shape
    return np.clip(0.5 + 0.2 * np.sin(np.arange(rows)[:, None] / 9.0) * np.cos(np.arange(cols)[None, :] / 7.0), 0, 1)


def table(heightmaps: dict, angles=DEFAULT_ANGLES, settings=DEFAULT_SETTINGS, height_scale=0.05, rays=4096,
          backend=None, progress=None) -> str:
    """Markdown table of probe-vs-reference accuracy for each height map x setting x angle."""
    lines = [
        "| height map | technique | params | angle | UV err mean | p95 | max (texels) | fetches mean | p95 | capped |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, height in heightmaps.items():
        for technique, params in settings:
            for angle in angles:
                a = measure(technique, height, angle, height_scale, rays, backend=backend, **params)
                label = ", ".join(f"{k}={v}" for k, v in params.items()) or "-"
                lines.append(
                    f"| {name} | {technique} | {label} | {angle:g}° | {a.error_mean:.3f} | {a.error_p95:.3f} | "
                    f"{a.error_max:.2f} | {a.fetches_mean:.1f} | {a.fetches_p95:.0f} | {a.capped:.1%} |"
                )
                if progress:
                    progress()
    return "\n".join(lines)
