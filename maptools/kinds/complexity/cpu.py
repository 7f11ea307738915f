"""The complexity kind's CPU reference: what the thesis' complexity_calculator.py runs (OpenCV)."""

from __future__ import annotations

import cv2
import numpy as np

from maptools.sobel import sobel


def dilation_radius(kernel: int, iterations: int) -> int:
    return (kernel // 2) * iterations


def complexity(height: np.ndarray, *, ksize: int = 3, dilate_kernel: int = 3, iterations: int = 5,
               gamma: float = 0.8, levels: int = 24, border: str = "reflect") -> np.ndarray:
    """Thesis complexity map as uint8 (H, W); defaults run exactly what complexity_calculator.py runs.

    Sobel -> magnitude -> / max -> dilate (kernel x kernel, iterations) -> C**gamma ->
    round(C/step)*step with step = 1/(levels-1) -> (C*255).astype(uint8). A flat map gives zeros.
    border="reflect" is OpenCV's default (reflect-101) with the dilation window clamped to the image;
    border="repeat" wraps both the Sobel and the dilation (tiling textures).
    """
    gx, gy = sobel(height, ksize, border)
    mag = np.square(gx, out=gx)  # in place: the same values as sqrt(gx ** 2 + gy ** 2), fewer temporaries
    mag += np.square(gy, out=gy)
    del gy
    np.sqrt(mag, out=mag)
    mx = np.max(mag)
    c = np.zeros_like(mag) if not mx > 0 else np.clip(np.divide(mag, mx, out=mag), 0, 1, out=mag)
    kernel = np.ones((dilate_kernel, dilate_kernel), np.uint8)
    if border == "repeat":
        r = dilation_radius(dilate_kernel, iterations)
        if r:
            p = np.pad(c, r, mode="wrap")
            c = np.ascontiguousarray(cv2.dilate(p, kernel, iterations=iterations)[r:-r, r:-r])
    elif iterations:
        c = cv2.dilate(c, kernel, iterations=iterations)
    c = np.power(c, gamma)
    step = 1.0 / (levels - 1)
    c = np.round(c / step) * step
    return (c * 255).astype(np.uint8)
