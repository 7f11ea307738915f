"""The complexity kind's GPU driver (``complexity.wgsl``: sobel_mag, dilate_h, dilate_v_finish)."""

from __future__ import annotations

import numpy as np

from maptools.gpu import MapGpu, guard, map_kernel
from maptools.sobel import BORDER_CODE

from .cpu import dilation_radius

KERNEL = map_kernel(__file__, "complexity.wgsl", [
    ("width", "u32"), ("height", "u32"), ("border", "u32"), ("ksize", "u32"),  # ksize: 3 or 5
    ("radius", "u32"),  # dilation radius = (kernel // 2) * iterations
    ("wrap_dilate", "u32"),  # 1: dilation wraps (repeat); 0: window clamped to the image (OpenCV's default)
    ("levels", "u32"), ("gamma", "f32"),
    ("step", "f32")])  # f32(1 / (levels - 1)), as numpy computes it


@guard(KERNEL)
def complexity(g: MapGpu, height: np.ndarray, *, ksize: int = 3, dilate_kernel: int = 3, iterations: int = 5,
               gamma: float = 0.8, levels: int = 24, border: str = "reflect"):
    """GPU twin of cpu.complexity (complexity.wgsl: sobel_mag, dilate_h, dilate_v_finish)."""
    h, w = height.shape
    g.check_size(h, w)
    src = g.storage(height, "maptools complexity src")
    mag = g.storage(h * w * 4, "maptools complexity magnitude")
    tmp = g.storage(h * w * 4, "maptools complexity dilated rows")
    out = g.storage(h * w * 4, "maptools complexity out")
    maxbits = g.storage(np.zeros(4, np.uint32), "maptools complexity max")
    step = float(np.float32(1.0 / (levels - 1)))
    params = g.uniform(KERNEL, {
        "width": w, "height": h, "border": BORDER_CODE[border], "ksize": ksize,
        "radius": dilation_radius(dilate_kernel, iterations), "wrap_dilate": 1 if border == "repeat" else 0,
        "levels": levels, "gamma": gamma, "step": step})
    enc = g.encoder("maptools complexity")
    g.dispatch(enc, KERNEL, "sobel_mag", {0: params, 1: src, 2: mag, 3: maxbits}, w, h)
    g.dispatch(enc, KERNEL, "dilate_h", {0: params, 1: mag, 2: tmp}, w, h)
    g.dispatch(enc, KERNEL, "dilate_v_finish", {0: params, 1: tmp, 2: out, 3: maxbits}, w, h)
    g.submit(enc)
    return g.read(out, h * w).reshape(h, w).astype(np.uint8)
