"""The maxmip kind's GPU driver (``maxmip.wgsl``, one dispatch per level)."""

from __future__ import annotations

import numpy as np

from maptools.gpu import MapGpu, guard, map_kernel

from .cpu import level_sizes

KERNEL = map_kernel(__file__, "maxmip.wgsl", [("src_size", "vec2u"), ("dst_size", "vec2u")])  # (w, h) of child, parent


@guard(KERNEL)
def maxmip(g: MapGpu, height: np.ndarray):
    """GPU twin of cpu.maxmip (maxmip.wgsl, one dispatch per level)."""
    sizes = level_sizes(*height.shape)
    g.check_size(*height.shape)
    bufs = [g.storage(height, "maptools maxmip level 0")]
    enc = g.encoder("maptools maxmip")
    for k, (ph, pw) in enumerate(sizes[1:], start=1):
        sh, sw = sizes[k - 1]
        bufs.append(g.storage(ph * pw * 4, f"maptools maxmip level {k}"))
        params = g.uniform(KERNEL, {"src_size": (sw, sh), "dst_size": (pw, ph)})
        g.dispatch(enc, KERNEL, "reduce", {0: params, 1: bufs[k - 1], 2: bufs[k]}, pw, ph)
    g.submit(enc)
    out = [height.copy()]
    for k, (ph, pw) in enumerate(sizes[1:], start=1):
        out.append(g.read(bufs[k], ph * pw).reshape(ph, pw))
    return out
