"""Turning an offscreen render into what a mode asks for, and writing files atomically."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import atomic_open

from .renderer import OffscreenImage

OUTPUT_MODES = ("color", "uv", "depth", "cost", "layers", "albedo")
OUTPUT_SUFFIXES = (".png", ".npy")


def mode_data(image: OffscreenImage, mode: str) -> np.ndarray:
    """Raw float32 data of a mode; NaN where nothing was drawn (except colour, which shows the background).

    color: (H, W, 3) the sRGB image in [0, 1] (albedo: the same of an image rendered with mode "albedo", the
    filtered albedo unlit); uv: (H, W, 2) hit UV (not wrapped);
    depth: (H, W) hit layer depth t; cost: (H, W) depth fetches per pixel; layers: (H, W) depth layers the
    search used (pom_adaptive's N; 0 for techniques without layers).
    """
    if mode in ("color", "albedo"):
        return image.color[:, :, :3].astype(np.float32) / 255.0
    covered = image.covered
    d = image.data
    if mode == "uv":
        out = d[:, :, 0:2].copy()
    elif mode == "depth":
        out = d[:, :, 2].copy()
    elif mode == "layers":
        out = (image.layers if image.layers is not None else np.zeros(d.shape[:2])).astype(np.float32)
    else:
        fetches = d[:, :, 3]
        out = np.where(fetches < 0, -fetches - 1.0, fetches).astype(np.float32)  # capped rays are stored negative
    out[~covered] = np.nan
    return out


def mode_picture(image: OffscreenImage, mode: str) -> np.ndarray:
    """(H, W, 3) uint8 RGB picture of a mode."""
    if mode in ("color", "albedo"):
        return image.color[:, :, :3].copy()
    data = mode_data(image, mode)
    covered = image.covered
    if mode == "uv":
        rgb = np.zeros(data.shape[:2] + (3,), np.float32)
        rgb[:, :, :2] = np.nan_to_num(data - np.floor(data))
        return np.rint(rgb * 255).astype(np.uint8)
    values = np.nan_to_num(data)
    if mode == "layers":  # the thesis' debug view: (N - Nmin) / (Nmax - Nmin) as grey
        lo, hi = image.layer_range
        values = (values - lo) / max(hi - lo, 1.0)
    if mode == "cost":
        peak = max(float(values.max()), 1.0)
        values = values / peak
    grey = np.clip(np.rint(values * 255), 0, 255).astype(np.uint8)
    if mode == "cost":
        rgb = cv2.cvtColor(cv2.applyColorMap(grey, cv2.COLORMAP_INFERNO), cv2.COLOR_BGR2RGB)
    else:
        rgb = np.repeat(grey[:, :, None], 3, axis=2)
    rgb[~covered] = 0
    return rgb


def save_rgb_png(path: Path, rgb: np.ndarray) -> None:
    ok, encoded = cv2.imencode(".png", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    if not ok:
        raise UserError(f"{path}: could not encode the PNG")
    with atomic_open(path) as f:  # readers never see a partial file
        f.write(encoded)


def save_output(path: Path, image: OffscreenImage, mode: str) -> None:
    path = Path(path)
    if path.suffix.lower() == ".npy":
        data = mode_data(image, mode)
        with atomic_open(path) as f:
            np.save(f, data)
    else:
        save_rgb_png(path, mode_picture(image, mode))
