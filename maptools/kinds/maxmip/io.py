"""The maxmip kind's file writer and reader."""

from __future__ import annotations

import numpy as np


def write_maxmip(f, levels: list, ext: str, bits: int = 8) -> None:
    """.npz with float32 arrays level0 (the input) ... levelK (1x1)."""
    np.savez(f, **{f"level{i}": np.asarray(a, np.float32) for i, a in enumerate(levels)})


def read_maxmip(path) -> list[np.ndarray]:
    with np.load(path) as z:
        return [z[f"level{i}"] for i in range(len(z.files))]
