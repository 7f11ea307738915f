"""Reading height maps and writing maps (atomically: temp file in the same folder, then os.replace)."""

from __future__ import annotations

import contextlib
import glob
import os
import tempfile
from pathlib import Path

import cv2
import numpy as np

from wgpuviewer.errors import UserError

CHANNELS = ("auto", "grey", "r", "g", "b", "a", "luma")
NAN_POLICIES = ("error", "zero", "nearest")
IMAGE_EXTS = (".png",)
INPUT_EXTS = (".png", ".npy")
_RGBA_INDEX = {"r": 0, "g": 1, "b": 2, "a": 3}  # in RGB(A) order


def validate_height(height, what: str = "height map") -> np.ndarray:
    """A finite float32 (H, W) array in [0, 1], C-contiguous; anything else is a UserError."""
    a = np.asarray(height)
    if a.ndim != 2:
        raise UserError(f"{what}: expected a 2-D (H, W) height map, got shape {a.shape}")
    if a.size == 0:
        raise UserError(f"{what}: empty height map {a.shape}")
    if not (np.issubdtype(a.dtype, np.floating) or np.issubdtype(a.dtype, np.integer)) or a.dtype == bool:
        raise UserError(f"{what}: unsupported dtype {a.dtype}; expected float heights in [0, 1]")
    a = np.ascontiguousarray(a, dtype=np.float32)
    bad = ~np.isfinite(a)
    if bad.any():
        raise UserError(f"{what}: {int(bad.sum())} NaN/inf texel(s); fix the data or choose --nan-policy zero|nearest")
    lo, hi = float(a.min()), float(a.max())
    if lo < 0.0 or hi > 1.0:
        raise UserError(f"{what}: heights must lie in [0, 1], found [{lo:g}, {hi:g}]; rescale the data")
    return a


def fill_nonfinite(a: np.ndarray, policy: str, what: str = "height map") -> np.ndarray:
    """Replace NaN/inf texels: error (refuse), zero, or nearest (value of the nearest finite texel, L2)."""
    if policy not in NAN_POLICIES:
        raise UserError(f"--nan-policy {policy!r}: expected one of {', '.join(NAN_POLICIES)}")
    bad = ~np.isfinite(a)
    if not bad.any() or policy == "error":
        return a
    a = a.copy()
    if policy == "zero":
        a[bad] = 0.0
        return a
    if bad.all():
        raise UserError(f"{what}: every texel is NaN/inf; nothing to fill from")
    # Each finite texel is a zero pixel with its own label (row-major order); every other texel gets the label
    # of its nearest zero pixel.
    _, labels = cv2.distanceTransformWithLabels(bad.astype(np.uint8), cv2.DIST_L2, 5,
                                                labelType=cv2.DIST_LABEL_PIXEL)
    values = a[~bad]
    a[bad] = values[labels[bad] - 1]
    return a


def _pick_channel(img: np.ndarray, channel: str, path: Path, rgb_order: bool) -> np.ndarray:
    if img.ndim == 2:
        if channel not in ("auto", "grey"):
            if img.ndim == 2 and channel in ("r", "g", "b", "luma"):
                return img  # a grey image has the same value in every colour channel
            raise UserError(f"{path}: grey image has no channel {channel!r}; use --channel auto")
        return img
    if img.ndim != 3 or img.shape[2] not in (1, 2, 3, 4):
        raise UserError(f"{path}: unsupported image shape {img.shape}")
    n = img.shape[2]
    if n <= 2:  # grey (+ alpha)
        if channel == "a" and n == 2:
            return img[:, :, 1]
        return img[:, :, 0]
    rgb = img[:, :, :3] if rgb_order else img[:, :, 2::-1]
    alpha = img[:, :, 3] if n == 4 else None
    if channel == "auto":
        if np.array_equal(rgb[:, :, 0], rgb[:, :, 1]) and np.array_equal(rgb[:, :, 0], rgb[:, :, 2]):
            return rgb[:, :, 0]
        raise UserError(f"{path}: colour image with different channels; choose --channel r|g|b|a|luma "
                        "(the thesis listing used b, its text r)")
    if channel == "grey":
        raise UserError(f"{path}: colour image; choose --channel r|g|b|a|luma")
    if channel == "a":
        if alpha is None:
            raise UserError(f"{path}: image has no alpha channel")
        return alpha
    if channel == "luma":
        f = rgb.astype(np.float64)
        return (0.299 * f[:, :, 0] + 0.587 * f[:, :, 1] + 0.114 * f[:, :, 2]) / _scale(img.dtype, path)
    return rgb[:, :, _RGBA_INDEX[channel]]


def _scale(dtype, path) -> float:
    if dtype == np.uint8:
        return 255.0
    if dtype == np.uint16:
        return 65535.0
    if np.issubdtype(dtype, np.floating):
        return 1.0
    raise UserError(f"{path}: unsupported pixel type {dtype}; expected 8/16-bit integers or floats")


def load_height_input(path, channel: str = "auto", nan_policy: str = "error") -> np.ndarray:
    """Height map file -> float32 (H, W) in [0, 1].

    8-bit PNG / uint8 arrays are divided by 255, 16-bit by 65535, floats are taken as they are (must lie in
    [0, 1]). ``.npy`` holds (H, W) or (H, W, C) in RGB(A) order. channel: auto (grey, or a colour image whose
    channels are equal), grey, r, g, b, a, luma (0.299 R + 0.587 G + 0.114 B). nan_policy: error, zero, nearest.
    """
    path = Path(path)
    if channel not in CHANNELS:
        raise UserError(f"--channel {channel!r}: expected one of {', '.join(CHANNELS)}")
    if nan_policy not in NAN_POLICIES:
        raise UserError(f"--nan-policy {nan_policy!r}: expected one of {', '.join(NAN_POLICIES)}")
    if not path.is_file():
        raise UserError(f"{path}: no such file")
    ext = path.suffix.lower()
    if ext == ".npy":
        try:
            raw = np.load(path, allow_pickle=False)
        except Exception as exc:  # noqa: BLE001 - any parse failure is the file's fault
            raise UserError(f"{path}: not a readable .npy file ({type(exc).__name__}: {exc})") from None
        rgb_order = True
    elif ext in IMAGE_EXTS:
        raw = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        if raw is None:
            raise UserError(f"{path}: not a readable PNG image")
        rgb_order = False  # OpenCV gives BGR(A)
    else:
        raise UserError(f"{path}: unsupported input type {ext or '(none)'}; expected .png or .npy")
    if raw.dtype == bool or not (np.issubdtype(raw.dtype, np.integer) or np.issubdtype(raw.dtype, np.floating)):
        raise UserError(f"{path}: unsupported data type {raw.dtype}")
    if raw.size == 0:
        raise UserError(f"{path}: empty image {raw.shape}")
    img = _pick_channel(raw, channel, path, rgb_order)
    if img.dtype in (np.uint8, np.uint16):
        img = img.astype(np.float32) / np.float32(_scale(img.dtype, path))
    elif np.issubdtype(img.dtype, np.integer):
        raise UserError(f"{path}: unsupported integer type {img.dtype}; use uint8/uint16 or floats in [0, 1]")
    img = fill_nonfinite(np.asarray(img, np.float32), nan_policy, str(path))
    return validate_height(img, str(path))


# -- writing ----------------------------------------------------------------------------------------


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_open(path):
    """Open a temp file ``.NAME.*.tmp`` next to ``path``; on success it replaces ``path`` (one rename), on any
    error it is removed. A process killed mid-write can leave only that hidden temp file, never a partial
    ``path``; ``remove_stale_temps`` clears such leftovers."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as error:
        raise UserError(f"{path}: cannot write here ({error.strerror or error}); choose another folder") from None
    try:
        with os.fdopen(fd, "wb") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600 files; outputs get the usual mode
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def remove_stale_temps(path) -> None:
    """Remove temp files a killed writer of ``path`` left behind (only call for outputs this process owns)."""
    path = Path(path)
    for tmp in path.parent.glob(f".{glob.escape(path.name)}.*.tmp"):
        with contextlib.suppress(OSError):
            tmp.unlink()


def _png_bytes(img: np.ndarray) -> bytes:
    ok, buf = cv2.imencode(".png", img)
    if not ok:
        raise UserError("could not encode PNG")
    return buf.tobytes()


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
    rgb = np.clip(np.rint((np.asarray(n, np.float64) + 1.0) * 0.5 * top), 0, top)
    rgb = rgb.astype(np.uint8 if bits == 8 else np.uint16)
    f.write(_png_bytes(np.ascontiguousarray(rgb[:, :, ::-1])))  # OpenCV writes BGR


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
    """.npy: float32 (Dz, H, W) volume (slice k = layer depth t in [k/Dz, (k+1)/Dz])."""
    np.save(f, np.asarray(vol, np.float32))


def write_result(kind, result, path, bits: int = 8) -> Path:
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in kind.extensions:
        raise UserError(f"{path}: {kind.name} maps are written as {', '.join(kind.extensions)}")
    with atomic_open(path) as f:
        kind.writer(f, result, ext, bits)
    return path


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
