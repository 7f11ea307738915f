"""The tie-back to relief mapping: how large texture coordinates (heavy ``uv_scale`` tiling) degrade the relief
techniques' hit uv.

A tiled surface hands each fragment's ray search an interpolated float32 uv of magnitude M (UV units; the texture
spans 1), so the entry point is already quantised to float32's spacing at M, and the search's own arithmetic
(``uv0 - t (V.xy / V.z) S``, bilinear weights from ``fract(uv * size)``) runs at M too. We trace the same random rays
with ``wgpuviewer.relief.probe.probe`` at entry points ``uv0 + M`` (a whole number of tiles: the same texture position
under repeat addressing) and compare with the float64 exact hit at ``uv0`` (``relief.reference.exact_hit``):

- ``raw``: the float32 entry point ``uv0 + M``, what a fragment of a heavily tiled surface gets;
- ``shader_fract``: that float32 value wrapped to [0, 1) in float32 before the search, what ``fract(uv)`` in the
  shader could do: the search runs at small coordinates, but the bits the entry point lost at M stay lost.

Wrapping per object (a float64 ``-floor(uv)`` offset per object or mesh tile, applied before the uv becomes float32)
gives exactly the M = 0 row: the entry point never reaches magnitude M.
"""

from __future__ import annotations

import numpy as np

from wgpuviewer.relief.accuracy import random_rays
from wgpuviewer.relief.probe import probe
from wgpuviewer.relief.reference import exact_hit, uv_error_texels
from wgpuviewer.textures import builtin_height

HEIGHT_MAP = "bumps"
ANGLE = 60.0  # degrees from the normal
HEIGHT_SCALE = 0.05
VARIANTS = ("raw", "shader_fract")


def spacing_texels(magnitude: float, texels: int) -> float:
    """float32's spacing at ``magnitude`` UV units, in texels of a ``texels``-wide texture."""
    return float(np.spacing(np.float32(max(magnitude, 1.0)))) * texels if magnitude > 0 else 0.0


def measure(techniques, magnitudes, rays: int, texels: int, backend: str | None = None, progress=None) -> list[dict]:
    """One row per technique x magnitude x variant: hit-uv error in texels against the float64 exact hit."""
    height = builtin_height(HEIGHT_MAP, (texels, texels)).astype(np.float64)
    uv0, view = random_rays(rays, ANGLE, seed=11)
    ref = exact_hit(1.0 - height, uv0, view, HEIGHT_SCALE)
    rows = []
    for technique in techniques:
        for magnitude in magnitudes:
            raw = (uv0 + magnitude).astype(np.float32)
            inputs = {"raw": raw, "shader_fract": raw - np.floor(raw)}  # float32 arithmetic, as a shader's fract
            for variant in VARIANTS:
                got = probe(technique, height, inputs[variant], view, HEIGHT_SCALE, backend=backend)
                ok = ~got.capped & ref.valid
                err = uv_error_texels(got.uv[ok].astype(np.float64), ref.uv[ok], (texels, texels))
                rows.append({
                    "technique": technique, "magnitude_uv": float(magnitude), "variant": variant,
                    "texels": texels, "rays": rays, "angle_deg": ANGLE,
                    "input_spacing_texels": spacing_texels(magnitude, texels),
                    "max_err": float(err.max()) if err.size else float("nan"),
                    "p99_err": float(np.percentile(err, 99)) if err.size else float("nan"),
                    "mean_err": float(err.mean()) if err.size else float("nan"),
                    "capped_fraction": float(got.capped.mean()),
                })
                if progress:
                    progress()
    return rows
