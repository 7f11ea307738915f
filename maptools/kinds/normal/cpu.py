"""The normal kind's CPU reference (OpenCV Sobel)."""

from __future__ import annotations

import numpy as np

from maptools.sobel import sobel


def normal(height: np.ndarray, *, strength: float = 1.0, y: str = "opengl", border: str = "repeat") -> np.ndarray:
    """Unit tangent-space normals, float32 (H, W, 3) in [-1, 1].

    x = -strength * dH/du, y = ysign * strength * dH/drow, z = 1, normalised; dH/d* is the Sobel
    3x3 response / 8 (height units per texel). ysign = +1 for y="opengl" (y axis towards row 0, "green up"),
    -1 for y="directx" (y axis towards increasing row = +v).
    """
    gx, gy = sobel(height, 3, border)
    ysign = np.float32(1.0 if y == "opengl" else -1.0)
    s = np.float32(strength)
    # Filled and normalised component by component: temporaries are one channel, not three (large maps).
    n = np.empty(gx.shape + (3,), np.float32)
    n[..., 0] = -s * gx * np.float32(0.125)
    del gx
    n[..., 1] = ysign * s * gy * np.float32(0.125)
    del gy
    n[..., 2] = 1.0
    length = n[..., 0] * n[..., 0]  # summed in the order of a reduction over the last axis
    length += n[..., 1] * n[..., 1]
    length += n[..., 2] * n[..., 2]
    np.sqrt(length, out=length)
    n /= length[..., None]
    return n
