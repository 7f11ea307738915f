"""Map kind ``complexity``: the adaptive-POM thesis' complexity map (Sobel magnitude, dilation, gamma, quantised
levels). Here: ``KIND`` (its registry entry, comparison and tolerance, cases), ``cpu`` (the OpenCV reference),
``gpu`` (the driver of ``complexity.wgsl``), ``io`` (its file writer) and ``slot`` (the renderer's ``complexity``
texture).

May import: ``wgpuviewer.core``, numpy, OpenCV, wgpu and maptools' shared modules; never another kind's folder.
"""

from __future__ import annotations

import math

import numpy as np

from maptools.registry import BORDER_HELP, Case, Comparison, Kind, Option
from maptools.sobel import BORDERS
from wgpuviewer.core.errors import UserError

from . import cpu, gpu, io

#: Complexity: sqrt, division and pow are not correctly rounded on every GPU; a difference of one ULP
#: before quantisation can flip a texel to the neighbouring level. Allowed: one level, on <= 0.1 % of texels.
COMPLEXITY_MAX_FLIPPED = 1e-3


def compare(a, b, opts) -> Comparison:
    d = np.abs(a.astype(np.int32) - b.astype(np.int32))
    mx = int(d.max()) if d.size else 0
    frac = float((d > 0).mean()) if d.size else 0.0
    step = math.ceil(255 / (opts["levels"] - 1))
    ok = mx <= step and frac <= COMPLEXITY_MAX_FLIPPED
    return Comparison(float(mx), float(d.mean()) if d.size else 0.0, ok,
                      f"{frac:.2e} of texels differ (allowed {COMPLEXITY_MAX_FLIPPED:g}, by at most one level = {step})")


def check(o: dict) -> None:
    if o["levels"] < 2:
        raise UserError(f"complexity: levels must be >= 2 (step = 1/(levels-1)), got {o['levels']}")
    if o["dilate_kernel"] % 2 == 0:
        raise UserError(f"complexity: dilate_kernel must be odd, got {o['dilate_kernel']}")
    if cpu.dilation_radius(o["dilate_kernel"], o["iterations"]) > 1024:
        raise UserError("complexity: dilation radius (dilate_kernel//2 * iterations) must be <= 1024")


KIND = Kind(
    name="complexity",
    description="complexity map of the adaptive-POM thesis (Sobel magnitude, dilation, gamma, quantised levels), 8-bit",
    options=(
        Option("ksize", 3, int, "Sobel kernel size (listing 3; 5 also allowed)", choices=(3, 5)),
        Option("dilate_kernel", 3, int, "dilation kernel size (listing 3, text 5)", lo=1, hi=99),
        Option("iterations", 5, int, "dilation iterations (listing 5)", lo=0, hi=1024),
        Option("gamma", 0.8, float, "gamma exponent (listing 0.8, text 0.9)", lo=1e-3, hi=100.0),
        Option("levels", 24, int, "number of quantisation levels N >= 2 (listing 24)", lo=-(2**31), hi=4096),
        Option("border", "reflect", str, BORDER_HELP + "; dilation wraps only with repeat", choices=BORDERS),
    ),
    cpu=cpu.complexity, gpu=gpu.complexity, compare=compare,
    tolerance=f"at most one quantisation level on <= {COMPLEXITY_MAX_FLIPPED:g} of texels (exact on lavapipe)",
    writer=io.write_complexity, extensions=(".png", ".npy"), check=check,
    cases=(Case({"border": "reflect"}), Case({"border": "repeat"})),
    order=20, readable=(2, np.uint8),
)
