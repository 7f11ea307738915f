"""The complexity kind's file writer."""

from __future__ import annotations

import numpy as np

from maptools.io import bits_check, png_bytes


def write_complexity(f, c: np.ndarray, ext: str, bits: int = 8) -> None:
    """.png: grey, 8-bit as computed (16-bit: value * 257, exact); .npy: the uint8 array."""
    if ext == ".npy":
        np.save(f, np.asarray(c, np.uint8))
        return
    bits_check(bits)
    img = np.asarray(c, np.uint8) if bits == 8 else np.asarray(c, np.uint16) * np.uint16(257)
    f.write(png_bytes(img))
