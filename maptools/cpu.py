"""CPU implementations of the map kinds (OpenCV where OpenCV has the operation, numpy otherwise).

They are the fallback when there is no GPU and the reference the GPU kernels are checked against.
Inputs are validated float32 height maps (H, W) in [0, 1]; rows are v (row 0 = v near 0), columns are u.
"""

from __future__ import annotations

import cv2
import numpy as np

BORDERS = ("repeat", "clamp", "reflect")
#: border name -> (OpenCV border type or None for "pad with numpy wrap first", WGSL constant)
_CV_BORDER = {"repeat": None, "clamp": cv2.BORDER_REPLICATE, "reflect": cv2.BORDER_REFLECT_101}
BORDER_CODE = {"repeat": 0, "clamp": 1, "reflect": 2}


def sobel(height: np.ndarray, ksize: int, border: str) -> tuple[np.ndarray, np.ndarray]:
    """cv2.Sobel(CV_32F) in x (columns, u) and y (rows) with the given border handling."""
    h = np.ascontiguousarray(height, dtype=np.float32)
    cvb = _CV_BORDER[border]
    if cvb is None:  # OpenCV filters have no wrap border: pad by the kernel radius, filter, crop
        r = ksize // 2
        p = np.pad(h, r, mode="wrap")
        gx = cv2.Sobel(p, cv2.CV_32F, 1, 0, ksize=ksize)[r:-r, r:-r]
        gy = cv2.Sobel(p, cv2.CV_32F, 0, 1, ksize=ksize)[r:-r, r:-r]
        return np.ascontiguousarray(gx), np.ascontiguousarray(gy)
    return (cv2.Sobel(h, cv2.CV_32F, 1, 0, ksize=ksize, borderType=cvb),
            cv2.Sobel(h, cv2.CV_32F, 0, 1, ksize=ksize, borderType=cvb))


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


def level_sizes(h: int, w: int) -> list[tuple[int, int]]:
    """(rows, cols) of every pyramid level: ceil halving down to 1x1."""
    sizes = [(h, w)]
    while sizes[-1] != (1, 1):
        hh, ww = sizes[-1]
        sizes.append(((hh + 1) // 2, (ww + 1) // 2))
    return sizes


def covered_range(i: int, n: int, p: int) -> tuple[int, int]:
    """Children [lo, hi] (inclusive) of parent i when n children reduce to p = ceil(n/2) parents."""
    return (i * n) // p, min(2 * i + 1, n - 1)


def _reduce_axis0(a: np.ndarray, p: int) -> np.ndarray:
    n = a.shape[0]
    out = np.empty((p,) + a.shape[1:], a.dtype)
    # Regular part: parents whose range is exactly 2i..2i+1; the rest (odd sizes) one by one.
    for i in range(p):
        lo, hi = covered_range(i, n, p)
        out[i] = a[lo:hi + 1].max(axis=0)
    return out


def maxmip(height: np.ndarray) -> list[np.ndarray]:
    """Maximum pyramid: list of float32 arrays, level 0 = the input, last = 1x1 (the global max).

    Parent i covers children floor(i*n/p) .. min(2i+1, n-1) per axis (p = ceil(n/2)), a superset of the
    index-space children 2i..2i+1 and of the children its UV span overlaps: conservative for odd sizes.
    """
    levels = [np.ascontiguousarray(height, dtype=np.float32)]
    for ph, pw in level_sizes(*height.shape)[1:]:
        a = levels[-1]
        if a.shape[0] % 2 == 0 and a.shape[1] % 2 == 0:
            b = a.reshape(ph, 2, pw, 2).max(axis=(1, 3))
        else:
            b = _reduce_axis0(_reduce_axis0(a, ph).T, pw).T
        levels.append(np.ascontiguousarray(b, dtype=np.float32))
    return levels
