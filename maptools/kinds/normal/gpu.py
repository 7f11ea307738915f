"""The normal kind's GPU driver (``normal.wgsl``)."""

from __future__ import annotations

import numpy as np

from maptools.gpu import MapGpu, guard, map_kernel
from maptools.sobel import BORDER_CODE

KERNEL = map_kernel(__file__, "normal.wgsl", [
    ("width", "u32"), ("height", "u32"), ("border", "u32"),  # border: the Sobel border (common/border.wgsl)
    ("strength", "f32"), ("ysign", "f32")])  # ysign: +1 OpenGL (y towards row 0), -1 DirectX


@guard(KERNEL)
def normal(g: MapGpu, height: np.ndarray, *, strength: float = 1.0, y: str = "opengl", border: str = "repeat"):
    """GPU twin of cpu.normal (normal.wgsl)."""
    h, w = height.shape
    g.check_size(h, w, 3)
    src = g.storage(height, "maptools normal src")
    dst = g.storage(h * w * 12, "maptools normal dst")
    params = g.uniform(KERNEL, {"width": w, "height": h, "border": BORDER_CODE[border],
                                "strength": strength, "ysign": 1.0 if y == "opengl" else -1.0})
    enc = g.encoder("maptools normal")
    g.dispatch(enc, KERNEL, "main", {0: params, 1: src, 2: dst}, w, h)
    g.submit(enc)
    return g.read(dst, h * w * 3).reshape(h, w, 3)
