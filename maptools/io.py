"""Checking height arrays, writing maps (atomically, through ``wgpuviewer.core.io.atomic_open``) and reading back the
maps a scene may name. Height files are read by ``wgpuviewer.core.images.read_height``, the reader scenes use too."""

from __future__ import annotations

import io
from pathlib import Path

import cv2
import numpy as np

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import atomic_open

#: Files ``maptools batch`` takes from input folders.
INPUT_EXTS = (".png", ".npy")


def validate_height(height, what: str = "height map", *, dtype=np.float32, error=UserError) -> np.ndarray:
    """A finite (H, W) array in [0, 1] of ``dtype``, C-contiguous; anything else raises ``error`` (a UserError
    here; the probe API raises InputError) naming ``what``."""
    a = np.asarray(height)
    if a.ndim != 2:
        raise error(f"{what}: expected a 2-D (H, W) height map, got shape {a.shape}")
    if a.size == 0:
        raise error(f"{what}: empty height map {a.shape}")
    if not (np.issubdtype(a.dtype, np.floating) or np.issubdtype(a.dtype, np.integer)) or a.dtype == bool:
        raise error(f"{what}: unsupported dtype {a.dtype}; expected float heights in [0, 1]")
    a = np.ascontiguousarray(a, dtype=dtype)
    bad = ~np.isfinite(a)
    if bad.any():
        raise error(f"{what}: {int(bad.sum())} NaN/inf texel(s); clean the data "
                    "(maptools: --nan-policy zero|nearest replaces them)")
    lo, hi = float(a.min()), float(a.max())
    if lo < 0.0 or hi > 1.0:
        raise error(f"{what}: heights must lie in [0, 1] (1 = top), found [{lo:g}, {hi:g}]; rescale the data")
    return a


def _png_bytes(img: np.ndarray) -> np.ndarray:
    """The encoded PNG (a uint8 array: file objects write it without a copy)."""
    ok, buf = cv2.imencode(".png", img)
    if not ok:
        raise UserError("could not encode PNG")
    return buf


def _bits_check(bits: int) -> None:
    if bits not in (8, 16):
        raise UserError(f"--bits {bits}: expected 8 or 16")


def write_normal(f, n: np.ndarray, ext: str, bits: int = 8) -> None:
    """.npy: float32 (H, W, 3); .png: RGB = round((n + 1) / 2 * (2^bits - 1))."""
    if ext == ".npy":
        np.save(f, np.asarray(n, np.float32))
        return
    _bits_check(bits)
    top = 255 if bits == 8 else 65535
    n = np.asarray(n)
    bgr = np.empty(n.shape, np.uint8 if bits == 8 else np.uint16)  # OpenCV writes BGR
    step = max(1, (1 << 16) // max(n.shape[1], 1))  # float64 in row bands: small temporaries at any size
    for row in range(0, n.shape[0], step):
        band = np.asarray(n[row:row + step], np.float64)
        bgr[row:row + step] = np.clip(np.rint((band + 1.0) * 0.5 * top), 0, top)[:, :, ::-1]
    f.write(_png_bytes(bgr))


def write_complexity(f, c: np.ndarray, ext: str, bits: int = 8) -> None:
    """.png: grey, 8-bit as computed (16-bit: value * 257, exact); .npy: the uint8 array."""
    if ext == ".npy":
        np.save(f, np.asarray(c, np.uint8))
        return
    _bits_check(bits)
    img = np.asarray(c, np.uint8) if bits == 8 else np.asarray(c, np.uint16) * np.uint16(257)
    f.write(_png_bytes(img))


def write_maxmip(f, levels: list, ext: str, bits: int = 8) -> None:
    """.npz with float32 arrays level0 (the input) ... levelK (1x1)."""
    np.savez(f, **{f"level{i}": np.asarray(a, np.float32) for i, a in enumerate(levels)})


def write_volume(f, vol, ext: str, bits: int = 8) -> None:
    """.npy: the volume as generated: float32 (Dz, H, W) (distance) or float16 (V, Dz, H, W) (distance_refined);
    slice k = layer depth t in [k/Dz, (k+1)/Dz]."""
    a = np.asarray(vol)
    np.save(f, a if a.dtype == np.float16 else a.astype(np.float32))


def write_result(kind, result, path, bits: int = 8) -> Path:
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in kind.extensions:
        raise UserError(f"{path}: {kind.name} maps are written as {', '.join(kind.extensions)}")
    with atomic_open(path) as f:
        kind.writer(f, result, ext, bits)
    return path


#: The maps a file can stand in for (a scene's ``[materials.X.maps]``): kind -> (dimensions, dtype) of the array it
#: holds as written (``write_complexity``, ``write_volume``, ``write_cone``).
READABLE = {"complexity": (2, np.uint8), "distance": (3, np.float32), "distance_refined": (4, np.float16),
            "cone": (2, np.float32)}


def read_map(kind: str, data: bytes, ext: str) -> np.ndarray:
    """The map of ``kind`` in a file's bytes ``data`` (extension ``ext``), as the kind's generator returns it: a
    complexity PNG's levels (16-bit: value / 257), a cone PNG decoded (``cone.decode_png``: never a wider cone), a
    .npy array as saved. A UserError says what the bytes hold instead."""
    dims, dtype = READABLE[kind]
    if ext == ".npy":
        try:
            a = np.load(io.BytesIO(data), allow_pickle=False)
        except (ValueError, OSError, EOFError) as error:
            raise UserError(f"not a readable .npy array ({error})") from None
    else:
        a = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
        if a is None or a.ndim != 2 or a.dtype not in (np.uint8, np.uint16):
            raise UserError("not a grey 8- or 16-bit PNG")
        if kind == "cone":
            from .cone import decode_png

            a = decode_png(a)
        elif a.dtype == np.uint16:
            a = (a // 257).astype(np.uint8)
    if a.ndim != dims or a.dtype != dtype:
        raise UserError(f"holds a {a.dtype} array of shape {a.shape}; a {kind} map is {dims}-D {np.dtype(dtype)}")
    return a


def read_maxmip(path) -> list[np.ndarray]:
    with np.load(path) as z:
        return [z[f"level{i}"] for i in range(len(z.files))]


def write_cone(f, c: np.ndarray, ext: str, bits: int = 8) -> None:
    """.npy: float32 (H, W) cone ratios; .png: grey floor((2^bits - 1) sqrt(c / 256)) (maptools.cone.decode_png)."""
    if ext == ".npy":
        np.save(f, np.asarray(c, np.float32))
        return
    _bits_check(bits)
    from .cone import encode_png

    f.write(_png_bytes(encode_png(c, bits)))
