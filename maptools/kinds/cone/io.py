"""The cone kind's file writer and its PNG encoding (a fixed scale, so a PNG decodes without options)."""

from __future__ import annotations

import numpy as np

from maptools.io import bits_check, png_bytes

from .cpu import to_float32_down

#: Fixed PNG scale (the largest allowed max_ratio): a PNG decodes without knowing the options.
PNG_SCALE = 256.0


def encode_png(c: np.ndarray, bits: int) -> np.ndarray:
    """value = floor((2^bits - 1) * sqrt(c / PNG_SCALE)), rounded down: the decoded cone is never wider."""
    top = (1 << bits) - 1
    x = np.clip(np.asarray(c, np.float64) * (1 - 1e-9) / PNG_SCALE, 0.0, 1.0)
    return np.floor(top * np.sqrt(x)).astype(np.uint8 if bits == 8 else np.uint16)


def decode_png(img: np.ndarray) -> np.ndarray:
    """Inverse of encode_png: c = PNG_SCALE * (value / (2^bits - 1))^2, float32, <= the stored ratio."""
    top = 255.0 if img.dtype == np.uint8 else 65535.0
    return to_float32_down(PNG_SCALE * (img.astype(np.float64) / top) ** 2)


def write_cone(f, c: np.ndarray, ext: str, bits: int = 8) -> None:
    """.npy: float32 (H, W) cone ratios; .png: grey floor((2^bits - 1) sqrt(c / 256)) (``decode_png``)."""
    if ext == ".npy":
        np.save(f, np.asarray(c, np.float32))
        return
    bits_check(bits)
    f.write(png_bytes(encode_png(c, bits)))
