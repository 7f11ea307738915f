"""Test height maps for the maptools tests."""

from __future__ import annotations

import numpy as np


def smooth_tileable(h: int, w: int, seed: int = 0, terms: int = 6) -> np.ndarray:
    """A smooth, periodic random relief in [0, 1] (sum of sines with integer frequencies)."""
    rng = np.random.default_rng(seed)
    y = np.arange(h)[:, None] / h
    x = np.arange(w)[None, :] / w
    z = np.zeros((h, w))
    for _ in range(terms):
        fx, fy = rng.integers(1, 5, 2)
        z += rng.random() * np.sin(2 * np.pi * (fx * x + fy * y) + rng.random() * 6.28)
    z -= z.min()
    return (z / z.max()).astype(np.float32) if z.max() > 0 else z.astype(np.float32)


def adversarial_maps() -> dict[str, np.ndarray]:
    """The hard cases of design.md plus realistic ones; all float32 in [0, 1]."""
    maps: dict[str, np.ndarray] = {}
    maps["smooth_64"] = smooth_tileable(64, 64, 1)
    maps["smooth_343x401"] = smooth_tileable(343, 401, 2)
    maps["flat0"] = np.zeros((32, 48), np.float32)
    maps["flat1"] = np.ones((32, 48), np.float32)
    spike = np.zeros((33, 31), np.float32)
    spike[16, 15] = 1.0
    maps["spike"] = spike
    step = np.zeros((40, 40), np.float32)
    step[:, 20:] = 1.0
    maps["step"] = step
    wall = np.zeros((40, 41), np.float32)
    wall[:, 20] = 1.0
    maps["wall"] = wall
    maps["checker"] = (np.indices((32, 32)).sum(axis=0) % 2).astype(np.float32)
    maps["one_texel"] = np.array([[0.25]], np.float32)
    maps["bits8"] = (np.round(smooth_tileable(50, 70, 3) * 255) / np.float32(255)).astype(np.float32)
    maps["bits16"] = (np.round(smooth_tileable(70, 50, 4) * 65535) / np.float32(65535)).astype(np.float32)
    maps["noise_odd"] = np.random.default_rng(5).random((17, 9)).astype(np.float32)
    return maps
