"""Map kind ``distance_refined``: the direction-binned refined distance map (Romanyuk et al. 2017). Here: ``KIND``
(its registry entry, comparison and tolerance, cases), ``cpu`` (the float64 reference and the size checks),
``bins`` (the direction bins and column lists), ``visibility`` (the paper's visibility condition), ``gpu`` (the
driver of ``distance_refined.wgsl``) and ``slot`` (the renderer's ``distance_refined`` volumes). The plain volume
it stacks last, and floors every value at, is the shared one of ``maptools/volume/``.

May import: ``wgpuviewer.core``, numpy, wgpu and maptools' shared modules (``volume`` among them); never another
kind's folder.
"""

from __future__ import annotations

import math

import numpy as np

from maptools.registry import Bench, Case, Comparison, Kind, Option, SampledReference
from maptools.volume import cpu as volume_cpu
from maptools.volume.io import write_volume

from . import cpu, gpu
from .bins import MAX_BANDS, SECTOR_CHOICES, VISIBILITY_CHOICES

#: Refined volumes (float16, rounded down): at most one float16 step of the larger value apart, or DISTANCE_TOL,
#: on all voxels (float32 vs float64 arithmetic may round the same value to neighbouring float16 numbers).
REFINED_REL_TOL = 2.0 ** -10


def compare(a, b, opts) -> Comparison:
    if np.shape(a) != np.shape(b):
        return Comparison(math.inf, math.inf, False, "shapes differ")
    a64, b64 = np.asarray(a, np.float64), np.asarray(b, np.float64)
    d = np.abs(a64 - b64)
    allowed = np.maximum(volume_cpu.DISTANCE_TOL, REFINED_REL_TOL * np.maximum(a64, b64))
    frac = float((d > 0).mean()) if d.size else 0.0
    return Comparison(float(d.max()) if d.size else 0.0, float(d.mean()) if d.size else 0.0,
                      bool((d <= allowed).all()), f"{frac:.2e} of values differ at all")


KIND = Kind(
    name="distance_refined",
    description="direction-binned refined distance map (Romanyuk et al. 2017), float16 (V, Dz, H, W) rounded down: one "
                "volume per bin of ray directions (azimuth sectors x polar bands of the view cone) with a safe "
                "step for every ray of that bin, then the plain map (steeper rays); nearest lookups",
    options=volume_cpu.VOLUME_OPTIONS + (
        Option("max_angle", 85.0, float, "half-angle of the binned view cone, degrees from the normal",
               lo=1.0, hi=89.0),
        Option("sectors", 4, int, "azimuth sectors (with bands 1: 1 = the single cone of the paper)",
               choices=SECTOR_CHOICES),
        Option("bands", 8, int, "polar bands, edges of equal cosine ratio: cos edge_k = cos(max_angle)^(k/bands)",
               lo=1, hi=MAX_BANDS),
        Option("reach", 16.0, float, "columns farther than this (texels, horizontally) are not looked at; "
               "values are capped near it", lo=1.0, hi=256.0),
        Option("visibility", "off", str, "the paper's visibility condition: on = each voxel bounded only for "
               "the directions that can reach it unblocked from the top (with sectors 1, bands 1: the paper's map)",
               choices=VISIBILITY_CHOICES),
    ),
    cpu=cpu.distance_refined, gpu=gpu.distance_refined, compare=compare,
    tolerance=f"|difference| <= max({volume_cpu.DISTANCE_TOL:g} texel, one float16 step) on every value",
    writer=write_volume, extensions=(".npy",),
    cases=(Case({"slices": 4, "height_scale": 0.3, "sectors": 2, "bands": 2}, 2048),
           Case({"slices": 4, "height_scale": 0.3, "sectors": 4, "bands": 5, "visibility": "on"}, 2048)),
    order=50, readable=(4, np.float16),
    sampled=SampledReference(cpu.sample_reference, lambda hw, o: (
        cpu.check(hw[1], hw[0], o["slices"], o["sectors"], o["bands"]), o["slices"], *hw)),
    bench=Bench("refined_sizes", "32,64",
                "comma-separated square sizes for distance_refined, 8 slices (default %(default)s)",
                {"slices": 8, "height_scale": 0.25}),
)
