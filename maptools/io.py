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


def png_bytes(img: np.ndarray) -> np.ndarray:
    """The encoded PNG (a uint8 array: file objects write it without a copy)."""
    ok, buf = cv2.imencode(".png", img)
    if not ok:
        raise UserError("could not encode PNG")
    return buf


def bits_check(bits: int) -> None:
    if bits not in (8, 16):
        raise UserError(f"--bits {bits}: expected 8 or 16")


def write_result(kind, result, path, bits: int = 8) -> Path:
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in kind.extensions:
        raise UserError(f"{path}: {kind.name} maps are written as {', '.join(kind.extensions)}")
    with atomic_open(path) as f:
        kind.writer(f, result, ext, bits)
    return path


def read_map(kind: str, data: bytes, ext: str) -> np.ndarray:
    """The map of ``kind`` in a file's bytes ``data`` (extension ``ext``), as the kind's generator returns it: a
    PNG through the kind's ``read_png`` (default: 16-bit values / 257), a .npy array as saved. Only kinds with
    ``readable`` (a scene's ``[materials.X.maps]``) are read. A UserError says what the bytes hold instead."""
    from .registry import get_kind

    k = get_kind(kind)
    if k.readable is None:
        raise UserError(f"{kind} maps are not read from files")
    dims, dtype = k.readable
    if ext == ".npy":
        try:
            a = np.load(io.BytesIO(data), allow_pickle=False)
        except (ValueError, OSError, EOFError) as error:
            raise UserError(f"not a readable .npy array ({error})") from None
    else:
        a = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
        if a is None or a.ndim != 2 or a.dtype not in (np.uint8, np.uint16):
            raise UserError("not a grey 8- or 16-bit PNG")
        if k.read_png is not None:
            a = k.read_png(a)
        elif a.dtype == np.uint16:
            a = (a // 257).astype(np.uint8)
    if a.ndim != dims or a.dtype != dtype:
        raise UserError(f"holds a {a.dtype} array of shape {a.shape}; a {kind} map is {dims}-D {np.dtype(dtype)}")
    return a
