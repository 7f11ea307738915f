"""The cone kind's GPU driver (``cone.wgsl``: ratio, then min3x3 for filter=bilinear)."""

from __future__ import annotations

import numpy as np

from maptools.gpu import MapGpu, guard, map_kernel

from .cpu import EXIT_BAND, STORE_MARGIN, check, ring_count

KERNEL = map_kernel(__file__, "cone.wgsl", [
    ("width", "u32"), ("height", "u32"), ("rings", "u32"), ("sy", "f32"), ("max_ratio", "f32"),
    ("keep", "f32"),  # 1 - store margin
    ("dmin", "f32"),  # global min depth
    ("band", "f32")])  # relative "may exit" band


@guard(KERNEL)
def cone(g: MapGpu, height: np.ndarray, *, max_ratio: float = 16.0, filter: str = "bilinear"):
    """GPU twin of cpu.cone (cone.wgsl: ratio, then min3x3 for filter=bilinear)."""
    h, w = height.shape
    check(w, h, max_ratio)
    g.check_size(h, w)
    dmin = float(np.min(np.float32(1.0) - height))
    src = g.storage(height, "maptools cone src")
    raw = g.storage(h * w * 4, "maptools cone raw")
    out = g.storage(h * w * 4, "maptools cone out")
    params = g.uniform(KERNEL, {"width": w, "height": h, "rings": ring_count(max_ratio, w, h), "sy": w / h,
                                "max_ratio": max_ratio, "keep": 1.0 - STORE_MARGIN, "dmin": dmin, "band": EXIT_BAND})
    enc = g.encoder("maptools cone")
    g.dispatch(enc, KERNEL, "ratio", {0: params, 1: src, 2: raw}, w, h)
    if filter == "bilinear":
        g.dispatch(enc, KERNEL, "min3x3", {0: params, 1: raw, 2: out}, w, h)
    g.submit(enc)
    return g.read(out if filter == "bilinear" else raw, h * w).reshape(h, w)
