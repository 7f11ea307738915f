"""Map kind ``maxmip``: the maximum pyramid. Here: ``KIND`` (its registry entry, comparison and tolerance, cases),
``cpu`` (the numpy reference and the level sizes), ``gpu`` (the driver of ``maxmip.wgsl``), ``io`` (its file writer
and reader) and ``slot`` (the renderer's ``maxmip`` atlas and the ``quadmax`` atlas, which packs the same levels).

May import: ``wgpuviewer.core``, numpy, wgpu and maptools' shared modules; never another kind's folder.
"""

from __future__ import annotations

import math

import numpy as np

from maptools.registry import Case, Comparison, Kind

from . import cpu, gpu, io


def compare(a, b, opts) -> Comparison:
    if len(a) != len(b) or any(x.shape != y.shape for x, y in zip(a, b)):
        return Comparison(math.inf, math.inf, False, "level count or shapes differ")
    diffs = [np.abs(x.astype(np.float64) - y) for x, y in zip(a, b)]
    mx = max(float(d.max()) for d in diffs)
    mean = float(np.mean([d.mean() for d in diffs]))
    return Comparison(mx, mean, mx == 0.0, f"{len(a)} levels")


KIND = Kind(
    name="maxmip",
    description="maximum pyramid: level 0 = height, each parent = max of the children it covers, down to 1x1",
    options=(),
    cpu=cpu.maxmip, gpu=gpu.maxmip, compare=compare,
    tolerance="exact (max is exact)",
    writer=io.write_maxmip, extensions=(".npz",), cases=(Case({}),),
    order=30,
)
