"""The image a perfect filter would give: per pixel n x n stratified sub-pixel rays (the centres of an n x n grid),
each traced to its exact first hit, the albedo taken there at level 0 (float64 bilinear, repeat), box-filtered;
and the same sub-pixel values weighted with EWA's Gaussian instead (``gauss``: exp(-alpha r^2) - exp(-alpha) for
r < 1 pixel from the pixel centre, the 3 x 3 neighbouring pixels' rays included), the reference a perfect EWA
would be measured against.

The rays are traced by the renderer itself at n times the resolution with the exact ``maxmip`` technique (its hit
uv comes back in the float32 data target); ``tests/lab/studies/filtering`` pins those hits to the float64
``exact_hit`` on the same rays and checks a flat relief against an analytic supersample computed from the
geometry alone. The albedo lookup is done here, in float64, on the linear albedo the renderer uploads, so no
GPU filtering enters the reference. Averages are taken in linear light and encoded to sRGB at the end, as the
renderer's sRGB target does.

Also from the sub-pixel hits: which pixels' footprints contain texels the relief hides (``occluded``): two
neighbouring sub-pixel rays (1/n pixel apart) whose hits lie far apart in texture space passed on both sides of
an occluding edge, so the texels between their hits are seen by no ray of the pixel.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from wgpuviewer.core.color import linear_to_srgb
from wgpuviewer.core.sampling import bilinear
from wgpuviewer.relief.renderer import DrawConfig, Renderer

from .views import TECHNIQUE, View, albedo_linear

#: A sub-pixel neighbour pair farther apart than this many texels, and than JUMP_FACTOR times the pixel's
#: median neighbour spacing, straddles an occluding edge.
JUMP_TEXELS = 1.5
JUMP_FACTOR = 6.0


@dataclass
class Supersample:
    n: int  # sub-pixel rays per pixel side
    color: np.ndarray  # (H, W, 3) float64 sRGB in [0, 1], the box-filtered reference
    gauss: np.ndarray  # (H, W, 3) float64 sRGB in [0, 1], Gaussian-weighted (EWA's kernel); the frame's border
    #: pixels use only the rays inside the frame
    covered: np.ndarray  # (H, W) bool: every sub-pixel ray hit the relief plane
    occluded: np.ndarray  # (H, W) bool: the footprint contains hidden texels
    hits: np.ndarray  # (H * n, W * n, 2) float32 sub-pixel hit uv (NaN where nothing was drawn)


def hit_uvs(renderer: Renderer, view: View, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Hit uv (H n, W n, 2) of the sub-pixel rays and where the plane was drawn, from an n-times render."""
    w, h = view.size
    image = renderer.render(DrawConfig.of(TECHNIQUE, filter="nearest"), (w * n, h * n), view.camera)
    uv = image.data[:, :, :2].copy()
    uv[~image.covered] = np.nan
    return uv, image.covered


def box_average(values: np.ndarray, n: int) -> np.ndarray:
    """(H n, W n, C) -> (H, W, C) mean over each n x n block."""
    hn, wn, c = values.shape
    return values.reshape(hn // n, n, wn // n, n, c).mean(axis=(1, 3))


def gaussian_average(values: np.ndarray, covered: np.ndarray, n: int, alpha: float = 2.0) -> np.ndarray:
    """(H n, W n, C) sub-pixel values -> (H, W, C): per pixel the weighted mean over the rays within 1 pixel of its
    centre, weights exp(-alpha r^2) - exp(-alpha) (r in pixels), only covered rays counted."""
    hn, wn, c = values.shape
    h, w = hn // n, wn // n
    blocks = (values * covered[..., None]).reshape(h, n, w, n, c)
    mask = covered.astype(np.float64).reshape(h, n, w, n, 1)
    offsets = (np.arange(n) + 0.5) / n - 0.5  # sub-pixel centres relative to their pixel's centre
    total = np.zeros((h, w, c))
    weight = np.zeros((h, w, 1))
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            ry, rx = np.meshgrid(offsets + dy, offsets + dx, indexing="ij")
            r2 = rx * rx + ry * ry
            k = np.where(r2 < 1.0, np.exp(-alpha * r2) - np.exp(-alpha), 0.0)[None, :, None, :, None]
            # the neighbour block (y + dy, x + dx) seen from pixel (y, x); outside the frame: nothing
            shifted = np.zeros_like(blocks)
            shifted_mask = np.zeros_like(mask)
            ys, yd = (slice(dy, None), slice(None, h - dy)) if dy >= 0 else (slice(None, dy), slice(-dy, None))
            xs, xd = (slice(dx, None), slice(None, w - dx)) if dx >= 0 else (slice(None, dx), slice(-dx, None))
            shifted[yd, :, xd] = blocks[ys, :, xs]
            shifted_mask[yd, :, xd] = mask[ys, :, xs]
            total += (shifted * k).sum(axis=(1, 3))
            weight += (shifted_mask * k).sum(axis=(1, 3))
    return total / np.maximum(weight, 1e-30)


def occluded_pixels(hits: np.ndarray, texels: tuple[int, int], n: int) -> np.ndarray:
    """(H, W) bool: pixels with a neighbouring sub-pixel pair whose hits jump across hidden texels: farther apart
    than JUMP_TEXELS and than JUMP_FACTOR times the pixel's median spacing in the same direction (at grazing views
    the rays along the view are many times farther apart than across it, on any relief)."""
    uv = hits.astype(np.float64) * np.asarray(texels, np.float64)
    hn, wn = uv.shape[:2]
    h, w = hn // n, wn // n
    occluded = np.zeros((h, w), bool)
    for axis in (1, 0):
        gaps = np.full((hn, wn), np.nan)
        step = np.linalg.norm(np.diff(uv, axis=axis), axis=-1)
        if axis == 1:
            gaps[:, :-1] = step
            gaps[:, n - 1::n] = np.nan  # pairs inside one pixel only
        else:
            gaps[:-1, :] = step
            gaps[n - 1::n, :] = np.nan
        blocks = gaps.reshape(h, n, w, n).transpose(0, 2, 1, 3).reshape(h, w, n * n)
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # blocks of uncovered rays are all NaN
            largest, median = np.nanmax(blocks, axis=-1), np.nanmedian(blocks, axis=-1)
        occluded |= (largest > JUMP_TEXELS) & (largest > JUMP_FACTOR * np.maximum(median, 1e-6))
    return occluded


def supersample(renderer: Renderer, view: View, n: int) -> Supersample:
    hits, covered = hit_uvs(renderer, view, n)
    albedo = np.asarray(albedo_linear(view), np.float64)
    values = np.zeros(hits.shape[:2] + (3,))
    values[covered] = bilinear(albedo, hits[covered].astype(np.float64))
    full = box_average(covered[..., None].astype(np.float64), n)[..., 0] == 1.0
    color = linear_to_srgb(np.clip(box_average(values, n), 0.0, 1.0))
    gauss = linear_to_srgb(np.clip(gaussian_average(values, covered, n), 0.0, 1.0))
    occluded = occluded_pixels(hits, albedo.shape[1::-1], n) & full
    return Supersample(n, color, gauss, full, occluded, hits)


def analytic_flat(view: View, n: int, depth: float) -> np.ndarray:
    """The supersampled reference of a flat relief at ``depth`` (layer depth, 0 = top), from the geometry alone:
    each sub-pixel ray meets the plane at uv0 and the relief at uv0 - depth (V.xy / V.z) S; linear average,
    sRGB-encoded. Independent of the renderer, the tracer and the GPU."""
    from .views import HEIGHT_SCALE

    uv0, v = view.entries(n)
    uv = uv0 - depth * v[..., :2] / v[..., 2:3] * HEIGHT_SCALE
    albedo = np.asarray(albedo_linear(view), np.float64)
    values = bilinear(albedo, uv.reshape(-1, 2)).reshape(uv.shape[:2] + (3,))
    return linear_to_srgb(np.clip(box_average(values, n), 0.0, 1.0))
