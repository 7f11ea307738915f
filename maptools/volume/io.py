"""The distance kinds' file writer."""

from __future__ import annotations

import numpy as np


def write_volume(f, vol, ext: str, bits: int = 8) -> None:
    """.npy: the volume as generated: float32 (Dz, H, W) (distance) or float16 (V, Dz, H, W) (distance_refined);
    slice k = layer depth t in [k/Dz, (k+1)/Dz]."""
    a = np.asarray(vol)
    np.save(f, a if a.dtype == np.float16 else a.astype(np.float32))
