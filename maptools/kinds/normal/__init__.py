"""Map kind ``normal``: unit tangent-space normals from Sobel 3x3 gradients. Here: ``KIND`` (its registry entry,
comparison and tolerance, cases), ``cpu`` (the OpenCV reference), ``gpu`` (the driver of ``normal.wgsl``) and
``io`` (its file writer). No slot: the renderer samples the material's own normal map.

May import: ``wgpuviewer.core``, numpy, OpenCV and maptools' shared modules; never another kind's folder.
"""

from __future__ import annotations

import numpy as np

from maptools.registry import BORDER_HELP, Case, Comparison, Kind, Option
from maptools.sobel import BORDERS

from . import cpu, gpu, io

#: Normal components: float rounding of sqrt/division differs by a few ULP between GPU and numpy.
NORMAL_TOL = 1e-5


def compare(a, b, opts) -> Comparison:
    d = np.abs(np.asarray(a, np.float64) - np.asarray(b, np.float64))
    mx = float(d.max()) if d.size else 0.0
    return Comparison(mx, float(d.mean()) if d.size else 0.0, mx <= NORMAL_TOL)


KIND = Kind(
    name="normal",
    description="unit tangent-space normals (H,W,3) from Sobel 3x3 gradients of the height map",
    options=(
        Option("strength", 1.0, float, "gradient scale: slope = strength * height units per texel", lo=0.0, hi=1e6),
        Option("y", "opengl", str, "y convention: opengl (+y towards row 0, green up) or directx (+y = +v, "
               "increasing row)", choices=("opengl", "directx")),
        Option("border", "repeat", str, BORDER_HELP, choices=BORDERS),
    ),
    cpu=cpu.normal, gpu=gpu.normal, compare=compare,
    tolerance=f"max |component difference| <= {NORMAL_TOL:g}",
    writer=io.write_normal, extensions=(".png", ".npy"),
    cases=(*(Case({"border": b}) for b in BORDERS), Case({"y": "directx", "strength": 4.0})),
    order=10,
)
