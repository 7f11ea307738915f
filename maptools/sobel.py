"""What the normal and complexity kinds' CPU references share: border handling and OpenCV's Sobel gradients.

The CPU references are the fallback when there is no GPU and the reference the GPU kernels are checked against.
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
