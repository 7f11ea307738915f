"""Map kind ``distance``: the plain 3D distance map (Donnelly 2005), box-exact on a sub-cell outer solid. Here:
``KIND`` (its registry entry, comparison and tolerance, cases), ``gpu`` (its driver) and ``slot`` (the renderer's
``distance`` volume). Its CPU reference, kernel (``distance.wgsl``) and writer are the plain volume's, which the
``distance_refined`` kind builds too: they live once, in ``maptools/volume/``.

May import: ``wgpuviewer.core``, numpy, wgpu and maptools' shared modules (``volume`` among them); never another
kind's folder.
"""

from __future__ import annotations

import math

import numpy as np

from maptools.registry import Bench, Case, Comparison, Kind, SampledReference
from maptools.volume import cpu as volume_cpu
from maptools.volume.io import write_volume

from . import gpu


def compare(a, b, opts) -> Comparison:
    if np.shape(a) != np.shape(b):
        return Comparison(math.inf, math.inf, False, "shapes differ")
    d = np.abs(np.asarray(a, np.float64) - np.asarray(b, np.float64))
    mx = float(d.max()) if d.size else 0.0
    return Comparison(mx, float(d.mean()) if d.size else 0.0, mx <= volume_cpu.DISTANCE_TOL)


KIND = Kind(
    name="distance",
    description="3D distance map (Donnelly 2005), float32 (Dz, H, W): per voxel the distance from the voxel box to an "
                "outer solid of sub-cell columns, in texels of u (v scaled by W/H, depth by S*W); a safe step for "
                "a nearest lookup anywhere in the voxel; periodic in u, v",
    options=volume_cpu.VOLUME_OPTIONS,
    cpu=volume_cpu.distance, gpu=gpu.distance, compare=compare,
    tolerance=f"max |difference| <= {volume_cpu.DISTANCE_TOL:g} texel",
    writer=write_volume, extensions=(".npy",),
    cases=(Case({"slices": 4, "height_scale": 0.3}, 2048), Case({"slices": 3, "subcells": 1}, 2048)),
    order=40, readable=(3, np.float32),
    sampled=SampledReference(volume_cpu.sample_reference, lambda hw, o: (o["slices"], *hw)),
    bench=Bench("volume_sizes", "32,64,128", "comma-separated square sizes for distance, 16 slices (default %(default)s)",
                {"slices": 16, "height_scale": 0.05}),
)
