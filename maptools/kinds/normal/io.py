"""The normal kind's file writer."""

from __future__ import annotations

import numpy as np

from maptools.io import bits_check, png_bytes


def write_normal(f, n: np.ndarray, ext: str, bits: int = 8) -> None:
    """.npy: float32 (H, W, 3); .png: RGB = round((n + 1) / 2 * (2^bits - 1))."""
    if ext == ".npy":
        np.save(f, np.asarray(n, np.float32))
        return
    bits_check(bits)
    top = 255 if bits == 8 else 65535
    n = np.asarray(n)
    bgr = np.empty(n.shape, np.uint8 if bits == 8 else np.uint16)  # OpenCV writes BGR
    step = max(1, (1 << 16) // max(n.shape[1], 1))  # float64 in row bands: small temporaries at any size
    for row in range(0, n.shape[0], step):
        band = np.asarray(n[row:row + step], np.float64)
        bgr[row:row + step] = np.clip(np.rint((band + 1.0) * 0.5 * top), 0, top)[:, :, ::-1]
    f.write(png_bytes(bgr))
