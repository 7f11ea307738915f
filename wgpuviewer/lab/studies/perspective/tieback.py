"""The tie-back to relief mapping: how large texture coordinates (heavy ``uv_scale`` tiling, large offsets) degrade
the relief techniques' hit uv.

A tiled surface hands each fragment's ray search an interpolated float32 uv of magnitude M (UV units; the texture
spans 1), so the entry point is already quantised to float32's spacing at M. The search itself runs on the entry
point's fraction: the probe (``relief.probe.probe``, repeat addressing) removes the whole tiles in float64 before
tracing and adds them back to the hit, as the renderer wraps uv per draw. We trace the same random rays at entry
points ``uv0 + M`` (a whole number of tiles: the same texture position under repeat addressing), rounded to
float32 as a fragment receives them, and compare with the float64 exact hit at ``uv0``
(``relief.reference.exact_hit``): what remains is the entry point's quantisation at M, carried through the search.

Keeping the coordinates small before they become float32 (a float64 ``-floor(uv)`` offset per object or mesh tile)
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
VARIANTS = ("float32_entry",)  # the entry point as a fragment receives it


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
            inputs = {"float32_entry": (uv0 + magnitude).astype(np.float32)}
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
