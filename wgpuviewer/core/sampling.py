"""CPU texture sampling with the GPU sampler's model: texel centres at (i + 0.5) / W, REPEAT (wrap) or CLAMP
(clamp-to-edge) addressing, nearest or ideal (float64) bilinear filtering, level 0. Used wherever the CPU must
agree with what a shader samples: the float64 reference, the benchmark's shading, the map tracers, the studies.
"""

from __future__ import annotations

import numpy as np

ADDRESS_MODES = ("repeat", "clamp")


def wrap_index(i: np.ndarray, n: int, address: str) -> np.ndarray:
    """Texel index ``i`` brought into [0, n) by the address mode."""
    return np.mod(i, n) if address == "repeat" else np.clip(i, 0, n - 1)


def check_address(address: str) -> None:
    if address not in ADDRESS_MODES:
        raise ValueError(f"address must be one of {ADDRESS_MODES}, got {address!r}")


def bilinear(texture: np.ndarray, uv: np.ndarray, address: str = "repeat") -> np.ndarray:
    """(H, W) or (H, W, C) ``texture`` at ``uv`` (N, 2): (N,) or (N, C) float64, bilinear between texel centres."""
    check_address(address)
    tex = np.asarray(texture)
    uv = np.asarray(uv, np.float64).reshape(-1, 2)
    h, w = tex.shape[:2]
    x = uv[:, 0] * w - 0.5
    y = uv[:, 1] * h - 0.5
    x0, y0 = np.floor(x), np.floor(y)
    fx, fy = x - x0, y - y0
    if tex.ndim == 3:
        fx, fy = fx[:, None], fy[:, None]
    i0 = wrap_index(x0.astype(np.int64), w, address)
    i1 = wrap_index(x0.astype(np.int64) + 1, w, address)
    j0 = wrap_index(y0.astype(np.int64), h, address)
    j1 = wrap_index(y0.astype(np.int64) + 1, h, address)
    t = tex.astype(np.float64, copy=False)
    top = t[j0, i0] * (1 - fx) + t[j0, i1] * fx
    bottom = t[j1, i0] * (1 - fx) + t[j1, i1] * fx
    return top * (1 - fy) + bottom * fy


def nearest(texture: np.ndarray, uv: np.ndarray, address: str = "repeat") -> np.ndarray:
    """(H, W) or (H, W, C) ``texture`` at ``uv`` (N, 2): the texel whose cell contains uv (GPU nearest filter)."""
    check_address(address)
    tex = np.asarray(texture)
    uv = np.asarray(uv, np.float64).reshape(-1, 2)
    h, w = tex.shape[:2]
    i = wrap_index(np.floor(uv[:, 0] * w).astype(np.int64), w, address)
    j = wrap_index(np.floor(uv[:, 1] * h).astype(np.int64), h, address)
    return tex[j, i].astype(np.float64)
