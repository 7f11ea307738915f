"""Map kind ``cone``: the relaxed cone map (Policarpo & Oliveira), conservative for the bilinear surface. Here:
``KIND`` (its registry entry, comparison and tolerance, cases), ``cpu`` (the float64 reference), ``gpu`` (the
driver of ``cone.wgsl``), ``io`` (its file writer and PNG encoding) and ``slot`` (the renderer's ``cone`` texture
and the map options it is built with).

May import: ``wgpuviewer.core``, numpy, wgpu and maptools' shared modules; never another kind's folder.
"""

from __future__ import annotations

import math

import numpy as np

from maptools.registry import Bench, Case, Comparison, Kind, Option, SampledReference

from . import cpu, gpu, io

#: Cone ratios: relative difference (float32 GPU arithmetic vs float64 CPU, both then lose the 2^-12 store margin).
CONE_REL_TOL = 1e-5
#: ... on all but this fraction of texels (a "may exit" decision inside the float band can flip; either result is
#: conservative). Measured 0 on lavapipe.
CONE_MAX_FLIPPED = 5e-3


def compare(a, b, opts) -> Comparison:
    if np.shape(a) != np.shape(b):
        return Comparison(math.inf, math.inf, False, "shapes differ")
    a64, b64 = np.asarray(a, np.float64), np.asarray(b, np.float64)
    rel = np.abs(a64 - b64) / np.maximum(np.maximum(a64, b64), 1e-6)
    frac = float((rel > CONE_REL_TOL).mean()) if rel.size else 0.0
    return Comparison(float(rel.max()) if rel.size else 0.0, float(rel.mean()) if rel.size else 0.0,
                      frac <= CONE_MAX_FLIPPED,
                      f"relative; {frac:.2e} of texels differ by > {CONE_REL_TOL:g} (allowed {CONE_MAX_FLIPPED:g})")


KIND = Kind(
    name="cone",
    description="relaxed cone map (Policarpo & Oliveira), float32 (H, W): cone ratio in texels of u per "
                "unit of layer depth t, conservative for the bilinear surface (docs/maps.md)",
    options=(
        Option("max_ratio", 16.0, float, "largest stored ratio (texels per unit t); bounds the search to "
               "about (2 max_ratio)^2 cells per texel", lo=0.25, hi=io.PNG_SCALE),
        Option("filter", "bilinear", str, "lookup the tracer uses: bilinear (3x3 min; safe for bilinear and "
               "nearest lookups) or nearest (larger cones, nearest lookups only)", choices=cpu.FILTERS),
    ),
    cpu=cpu.cone, gpu=gpu.cone, compare=compare,
    tolerance=f"relative difference <= {CONE_REL_TOL:g} on all but {CONE_MAX_FLIPPED:g} of texels",
    writer=io.write_cone, extensions=(".npy", ".png"),
    cases=(Case({"filter": "nearest"}, 2048), Case({"filter": "bilinear"}, 2048)),
    order=60, readable=(2, np.float32), read_png=io.decode_png,
    sampled=SampledReference(cpu.sample_reference, lambda hw, o: hw),
    bench=Bench("cone_sizes", "64,128", "comma-separated square sizes for cone, max_ratio 16 (default %(default)s)", {}),
)
