"""Turning an offscreen render into what a mode asks for, and writing files atomically.

The modes (``OUTPUT_MODES``): ``color`` the shaded picture; ``albedo`` the filtered albedo, unlit (render it with
mode "albedo"); ``uv`` the hit's uv; ``depth`` camera depth: the traced hit's distance from the camera along its
view axis, in scene units (linear view-space depth, what a compositor's Z pass holds; ``OffscreenImage.view_depth``);
``layer_depth`` the hit's depth t inside the relief (0 = top, 1 = the deepest the relief goes); ``cost`` depth
fetches per pixel; ``layers`` the depth layers the search used.

A ``.npy`` holds a mode's raw float32 data, NaN where nothing was drawn (colour and albedo show the background
there); a ``.png`` a picture of it. ``alpha``: the picture is RGBA, transparent where nothing was drawn, so a
render composites over another image; colour and albedo data get a fourth channel, 1 where drawn and 0 elsewhere.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import atomic_open

from .targets import OffscreenImage

#: What each output mode writes (the module docstring has the detail; `render --mode`'s help lists these).
MODE_DESCRIPTIONS = {
    "color": "the shaded picture",
    "depth": "camera depth: the hit's distance from the camera along its view axis, in scene units",
    "layer_depth": "the hit's depth inside the relief, 0 = top",
    "uv": "the hit's uv",
    "cost": "depth fetches per pixel",
    "layers": "depth layers the search used",
    "albedo": "the filtered albedo, unlit",
}
OUTPUT_MODES = tuple(MODE_DESCRIPTIONS)
OUTPUT_SUFFIXES = (".png", ".npy")


def mode_data(image: OffscreenImage, mode: str, alpha: bool = False) -> np.ndarray:
    """Raw float32 data of a mode (module docstring); NaN where nothing was drawn, except colour and albedo.

    color, albedo: (H, W, 3) the sRGB image in [0, 1], (H, W, 4) with ``alpha`` (1 where drawn, 0 elsewhere);
    uv: (H, W, 2) hit UV (not wrapped); depth: (H, W) camera depth in scene units; layer_depth: (H, W) hit layer
    depth t; cost: (H, W) depth fetches per pixel; layers: (H, W) depth layers the search used (pom_adaptive's N; 0
    for techniques without layers).
    """
    covered = image.covered
    if mode in ("color", "albedo"):
        rgb = image.color[:, :, :3].astype(np.float32) / 255.0
        return np.dstack([rgb, covered.astype(np.float32)]) if alpha else rgb
    d = image.data
    if mode == "uv":
        out = d[:, :, 0:2].copy()
    elif mode == "depth":
        out = image.view_depth.astype(np.float32, copy=True)
    elif mode == "layer_depth":
        out = d[:, :, 2].copy()
    elif mode == "layers":
        out = (image.layers if image.layers is not None else np.zeros(d.shape[:2])).astype(np.float32)
    else:
        fetches = d[:, :, 3]
        out = np.where(fetches < 0, -fetches - 1.0, fetches).astype(np.float32)  # capped rays are stored negative
    out[~covered] = np.nan
    return out


def mode_picture(image: OffscreenImage, mode: str, alpha: bool = False) -> np.ndarray:
    """(H, W, 3) uint8 RGB picture of a mode, (H, W, 4) RGBA with ``alpha`` (0 where nothing was drawn). depth:
    the nearest drawn pixel white, the farthest black; layer_depth: t as grey (0 = top black)."""
    rgb = image.color[:, :, :3].copy() if mode in ("color", "albedo") else _data_picture(image, mode)
    if alpha:
        return np.dstack([rgb, np.where(image.covered, 255, 0).astype(np.uint8)])
    return rgb


def _data_picture(image: OffscreenImage, mode: str) -> np.ndarray:
    data = mode_data(image, mode)
    covered = image.covered
    if mode == "uv":
        rgb = np.zeros(data.shape[:2] + (3,), np.float32)
        rgb[:, :, :2] = np.nan_to_num(data - np.floor(data))
        return np.rint(rgb * 255).astype(np.uint8)
    values = np.nan_to_num(data)
    if mode == "depth" and covered.any():
        near, far = float(values[covered].min()), float(values[covered].max())
        values = (far - values) / max(far - near, 1e-12)
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
    """Write an (H, W, 3) RGB or (H, W, 4) RGBA uint8 picture as a PNG, atomically."""
    order = cv2.COLOR_RGBA2BGRA if rgb.shape[2] == 4 else cv2.COLOR_RGB2BGR
    ok, encoded = cv2.imencode(".png", cv2.cvtColor(rgb, order))
    if not ok:
        raise UserError(f"{path}: could not encode the PNG")
    with atomic_open(path) as f:  # readers never see a partial file
        f.write(encoded)


def save_output(path: Path, image: OffscreenImage, mode: str, alpha: bool = False) -> None:
    """A mode of ``image`` as ``path``: raw float32 data (.npy) or a picture (.png); ``alpha`` as in the module
    docstring."""
    path = Path(path)
    if path.suffix.lower() == ".npy":
        data = mode_data(image, mode, alpha)
        with atomic_open(path) as f:
            np.save(f, data)
    else:
        save_rgb_png(path, mode_picture(image, mode, alpha))
