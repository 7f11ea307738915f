"""Colour on the CPU: the sRGB transfer functions and the heat ramp of the cost and error views (the same ramp
as ``wgsl/common/heat.wgsl``, which the cost and error views draw with; the HUD legend uses this one)."""

from __future__ import annotations

import numpy as np


def srgb_to_linear(c) -> np.ndarray:
    """Decode sRGB-encoded values in [0, 1] (the standard piecewise transfer function), float32."""
    c = np.asarray(c, np.float32)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def linear_to_srgb(c) -> np.ndarray:
    """Encode linear values in [0, 1] as sRGB (float64 in, float64 out)."""
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * np.power(np.maximum(c, 0.0), 1 / 2.4) - 0.055)


def heat(x) -> np.ndarray:
    """Heat ramp black -> red -> yellow -> white for x in [0, 1] (clamped), linear RGB, shape (..., 3)."""
    s = np.clip(np.asarray(x, np.float64), 0.0, 1.0)[..., None] * 3.0
    return np.clip(s - np.array([0.0, 1.0, 2.0]), 0.0, 1.0)
