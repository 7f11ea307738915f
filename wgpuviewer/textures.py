"""Texture data for scenes: builtin generators and image/array files, loaded lazily from TextureRef.

Conventions: arrays are float32, row 0 is the top of the image (v = 0), column 0 is u = 0.
Heights are in [0, 1] with 1 = top; the GPU gets depth = 1 - height. Albedo is linear RGB.
Loaded arrays are cached (several techniques share them) and returned read-only.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

import cv2
import numpy as np

from .errors import UserError

if TYPE_CHECKING:  # scene.py imports BUILTINS from here
    from .scene import TextureRef

# ----------------------------------------------------------------------------------------------
# Builtin textures. Each generator maps (width, height) to (height map, albedo). Relief builtins
# are functions of (u, v) with period 1, so they tile at any size and look the same at any size.

_Generated = tuple[np.ndarray, np.ndarray]


def _uv(w: int, h: int) -> tuple[np.ndarray, np.ndarray]:
    """Texel-centre coordinates in [0, 1), each shaped (h, w)."""
    return np.meshgrid((np.arange(w) + 0.5) / w, (np.arange(h) + 0.5) / h)


def _noise(shape: tuple[int, int], seed: int, terms: int = 24, max_freq: int = 12) -> np.ndarray:
    """Periodic noise (h, w) in [-1, 1]: cosines with integer frequencies (so it tiles) and 1/f
    amplitudes, summed by an inverse FFT of their sparse spectrum (fast at any size)."""
    h, w = shape
    rng = np.random.default_rng(seed)
    spectrum = np.zeros(shape, np.complex128)
    total = 0.0
    for _ in range(terms):
        fx, fy = rng.integers(-max_freq, max_freq + 1, 2)
        phase = rng.uniform(0, 2 * np.pi)
        if fx == fy == 0:
            continue
        amp = 1.0 / np.hypot(fx, fy)
        # The FFT samples texel corners; texels are sampled at their centres, half a texel on.
        spectrum[fy % h, fx % w] += amp * np.exp(1j * (phase + np.pi * (fx / w + fy / h)))
        total += amp
    return np.fft.ifft2(spectrum).real * (h * w / total)


def _smoothstep(e0: float, e1: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3 - 2 * t)


def _mix(a, b, t: np.ndarray) -> np.ndarray:
    """Per-texel blend of colours a and b (broadcast (..., 3)) by t (h, w)."""
    return np.asarray(a) * (1 - t[..., None]) + np.asarray(b) * t[..., None]


def _bricks(w: int, h: int) -> _Generated:
    rows, cols = 4, 2  # per tile; even row count keeps the half-brick offset periodic
    u, v = _uv(w, h)
    y = v * rows
    row = np.floor(y).astype(int)
    x = u * cols + 0.5 * (row % 2)
    col = np.floor(x).astype(int) % cols  # a brick cut by the tile edge is one brick
    fx, fy = x - np.floor(x), y - row
    # Distance to the brick's edge in UV units, so the mortar is equally wide both ways.
    edge = np.minimum(np.minimum(fx, 1 - fx) / cols, np.minimum(fy, 1 - fy) / rows)
    face = _smoothstep(0.012, 0.03, edge)
    rng = np.random.default_rng(1)
    brick = rng.random((rows, cols, 3))[row, col]
    grain = _noise(u.shape, seed=2, max_freq=24)
    height = 0.12 + (0.7 + 0.1 * brick[..., 0]) * face + 0.04 * grain
    red = np.array([0.32, 0.085, 0.045]) * (0.7 + 0.6 * brick[..., 1:2]) + 0.03 * (brick[..., 2:3] - 0.5)
    mortar = np.array([0.4, 0.39, 0.36]) * (1 + 0.15 * grain[..., None])
    albedo = _mix(mortar, red * (1 + 0.2 * grain[..., None]), face)
    return height, albedo


def _bumps(w: int, h: int) -> _Generated:
    cells = 4  # per tile; each dome stays inside its cell, so only the own cell matters
    u, v = _uv(w, h)
    x, y = u * cells, v * cells
    i, j = np.floor(x).astype(int), np.floor(y).astype(int)
    rng = np.random.default_rng(3)
    centre = 0.5 + rng.uniform(-0.06, 0.06, (cells, cells, 2))[j, i]
    radius = rng.uniform(0.3, 0.42, (cells, cells))[j, i]
    peak = rng.uniform(0.7, 1.0, (cells, cells))[j, i]
    r = np.hypot(x - i - centre[..., 0], y - j - centre[..., 1]) / radius
    dome = np.clip(1 - r * r, 0, 1) ** 2  # smooth at the rim, so derived normals do not jump
    ground = 0.08 + 0.05 * _noise(u.shape, seed=4)
    height = ground + (peak - ground) * dome
    tint = _mix([0.45, 0.37, 0.25], [0.09, 0.26, 0.24], _smoothstep(0.0, 0.15, dome))
    albedo = tint * (1 + 0.12 * _noise(u.shape, seed=5, max_freq=20)[..., None])
    return height, albedo


def _ridges(w: int, h: int) -> _Generated:
    u, v = _uv(w, h)
    # |sin(pi * t)| has period 1 in t: integer ridge count plus a periodic wobble keeps it tileable.
    t = 6 * u + 0.35 * np.sin(2 * np.pi * 2 * v)
    height = 0.85 * (1 - np.abs(np.sin(np.pi * t))) + 0.07 + 0.05 * _noise(u.shape, seed=6)
    albedo = _mix([0.16, 0.1, 0.06], [0.62, 0.47, 0.3], np.clip(height, 0, 1))
    return height, albedo


def _test_pattern(height: np.ndarray) -> _Generated:
    """Albedo for the hard cases: grey by height on a faint 32-texel checker, so motion shows."""
    ys, xs = np.indices(height.shape)
    check = 0.9 + 0.1 * ((xs // 32 + ys // 32) % 2)
    grey = (0.2 + 0.6 * height) * check
    return height, np.repeat(grey[..., None], 3, axis=2)


def _hard(fn: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> Callable[[int, int], _Generated]:
    """Hard case from a function of texel indices (ys, xs) -> exact 0/1 heights."""

    def generate(w: int, h: int) -> _Generated:
        ys, xs = np.indices((h, w))
        return _test_pattern(fn(ys, xs).astype(np.float64))

    return generate


#: Builtin name -> generator (width, height) -> (height map (h, w), albedo (h, w, 3)).
BUILTINS: dict[str, Callable[[int, int], _Generated]] = {
    "bricks": _bricks,
    "bumps": _bumps,
    "ridges": _ridges,
    "flat0": _hard(lambda ys, xs: np.zeros(xs.shape)),
    "flat1": _hard(lambda ys, xs: np.ones(xs.shape)),
    "spike": _hard(lambda ys, xs: (ys == ys.shape[0] // 2) & (xs == xs.shape[1] // 2)),
    "step": _hard(lambda ys, xs: xs >= xs.shape[1] // 2),
    "wall": _hard(lambda ys, xs: xs == xs.shape[1] // 2),
    "checker": _hard(lambda ys, xs: (xs // 8 + ys // 8) % 2),
}

#: Largest builtin side; the WebGPU default limit for 2D textures.
MAX_BUILTIN_SIZE = 8192


def _read_only(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


@lru_cache(maxsize=32)
def _builtin(name: str, size: tuple[int, int]) -> _Generated:
    if name not in BUILTINS:
        raise UserError(f"builtin texture {name!r}: unknown; expected one of {', '.join(BUILTINS)}")
    w, h = size
    if not (1 <= w <= MAX_BUILTIN_SIZE and 1 <= h <= MAX_BUILTIN_SIZE):
        raise UserError(f"builtin texture {name!r}: size {size}: expected 1 to {MAX_BUILTIN_SIZE} per side")
    height, albedo = BUILTINS[name](w, h)
    height = np.clip(height, 0, 1).astype(np.float32)
    albedo = np.clip(albedo, 0, 1).astype(np.float32)
    return _read_only(height), _read_only(albedo)


def builtin_height(name: str, size: tuple[int, int] = (256, 256)) -> np.ndarray:
    """Height map (h, w) float32 in [0, 1] of a builtin; size is (width, height)."""
    return _builtin(name, tuple(size))[0]


def builtin_albedo(name: str, size: tuple[int, int] = (256, 256)) -> np.ndarray:
    """Linear RGB albedo (h, w, 3) float32 in [0, 1] matching the builtin's relief."""
    return _builtin(name, tuple(size))[1]


# ----------------------------------------------------------------------------------------------
# Files.

_CHANNELS = "rgba"


def read_image(path, channel: str = "auto") -> np.ndarray:
    """Image file (8/16-bit PNG, JPEG, TIFF, ...) or .npy array as float32 scaled to [0, 1].

    Integers are divided by their maximum (255 or 65535); float data is returned as is (callers
    check the range). Returns (h, w) for grey data or a named channel ('r', 'g', 'b', 'a'), else
    (h, w, 3|4) in RGB(A) order. .npy colour data is taken as RGB(A), image files are BGR(A) in
    OpenCV and reordered here.
    """
    path = Path(path)
    if not path.is_file():
        raise UserError(f"{path}: file not found")
    if path.suffix.lower() == ".npy":
        try:
            data = np.load(path, allow_pickle=False)
        except (OSError, ValueError) as e:
            raise UserError(f"{path}: cannot read .npy array ({e}); save it with numpy.save") from None
    else:
        # imdecode instead of imread: same decoders, but handles non-ASCII paths everywhere.
        data = cv2.imdecode(np.fromfile(path, np.uint8), cv2.IMREAD_UNCHANGED)
        if data is None:
            raise UserError(f"{path}: cannot decode image (corrupt or unsupported format); use PNG, JPEG or .npy")
        if data.ndim == 3 and data.shape[2] in (3, 4):
            data = data[..., [2, 1, 0, 3][: data.shape[2]]]
    if data.size == 0:
        raise UserError(f"{path}: empty image (shape {data.shape})")
    if data.ndim == 3 and data.shape[2] == 1:
        data = data[..., 0]
    if not (data.ndim == 2 or (data.ndim == 3 and data.shape[2] in (3, 4))):
        raise UserError(f"{path}: unsupported shape {data.shape}; expected (h, w), (h, w, 3) or (h, w, 4)")
    if data.dtype == np.uint8:
        data = data.astype(np.float32) / 255
    elif data.dtype == np.uint16:
        data = data.astype(np.float32) / 65535
    elif data.dtype.kind == "f":
        data = data.astype(np.float32)
        bad = int(np.count_nonzero(~np.isfinite(data)))
        if bad:
            raise UserError(f"{path}: {bad} non-finite values (NaN/inf); clean the data or replace non-finite values")
    else:
        raise UserError(f"{path}: unsupported dtype {data.dtype}; expected uint8, uint16 or float")
    if channel == "auto":
        return data
    if channel not in _CHANNELS:
        raise UserError(f"{path}: channel {channel!r}: unknown; expected auto, r, g, b or a")
    present = _CHANNELS[: data.shape[2]] if data.ndim == 3 else ""
    if channel not in present:
        kind = f"{data.shape[2]}-channel" if present else "greyscale"
        raise UserError(f"{path}: channel {channel!r} requested but the image is {kind}; use channel 'auto'"
                        + (f" or one of {', '.join(present)}" if present else ""))
    return data[..., present.index(channel)]


def _check_unit_range(data: np.ndarray, path: Path, what: str) -> None:
    lo, hi = float(data.min()), float(data.max())
    if lo < 0 or hi > 1:
        raise UserError(f"{path}: {what} values range from {lo:g} to {hi:g}; expected 0 to 1 (normalise the data)")


def _luminance(rgb: np.ndarray) -> np.ndarray:
    """Rec. 709 luma of the stored values: a colour height map is data, so no sRGB decoding."""
    return rgb[..., :3] @ np.array([0.2126, 0.7152, 0.0722], np.float32)


def _srgb_to_linear(c: np.ndarray) -> np.ndarray:
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


@lru_cache(maxsize=64)
def load_height(ref: TextureRef, is_depth: bool = False) -> np.ndarray:
    """Height (h, w) float32 in [0, 1], 1 = top. With is_depth the source holds depth (0 = top)."""
    if ref.kind == "builtin":
        data = builtin_height(ref.name, ref.size)
    elif ref.kind == "file":
        data = read_image(ref.path, ref.channel)
        if data.ndim == 3:
            data = _luminance(data)
        _check_unit_range(data, ref.path, "depth" if is_depth else "height")
    else:
        raise UserError(f"a {ref.kind} texture cannot be a height map; use a builtin or a file")
    return _read_only((1 - data if is_depth else data).astype(np.float32))


@lru_cache(maxsize=64)
def load_depth(ref: TextureRef, is_depth: bool = False) -> np.ndarray:
    """Depth (h, w) float32 in [0, 1], 0 = top: what the GPU samples."""
    return _read_only(1 - load_height(ref, is_depth))


@lru_cache(maxsize=64)
def load_albedo(ref: TextureRef) -> np.ndarray:
    """Linear RGB albedo (h, w, 3) float32 in [0, 1]; a colour is a 1x1 texture.

    File data is taken as sRGB-encoded (as image editors save it) and decoded with the standard
    sRGB transfer function; grey files are expanded to RGB, alpha is dropped.
    """
    if ref.kind == "color":
        data = np.array(ref.color, np.float32).reshape(1, 1, 3)
    elif ref.kind == "builtin":
        return builtin_albedo(ref.name, ref.size)
    else:
        data = read_image(ref.path)
        _check_unit_range(data, ref.path, "albedo")
        data = np.repeat(data[..., None], 3, axis=2) if data.ndim == 2 else data[..., :3]
        data = _srgb_to_linear(data)
    return _read_only(np.ascontiguousarray(data, np.float32))


@lru_cache(maxsize=32)
def load_normal_map(ref: TextureRef, normal_y: str = "opengl") -> np.ndarray:
    """Unit tangent-space normals (h, w, 3) float32, OpenGL convention (+Y = green up).

    The file stores n * 0.5 + 0.5 per channel (the usual encoding, also for float .npy).
    DirectX maps have green pointing down, so their y is negated.
    """
    if ref.kind != "file":
        raise UserError(f"a {ref.kind} texture cannot be a normal map; omit it to derive normals from the height map")
    if normal_y not in ("opengl", "directx"):
        raise UserError(f"normal_y {normal_y!r}: unknown; expected opengl or directx")
    data = read_image(ref.path)
    if data.ndim != 3:
        raise UserError(f"{ref.path}: normal map is greyscale; expected an RGB image")
    _check_unit_range(data, ref.path, "normal map")
    n = data[..., :3] * 2 - 1
    if normal_y == "directx":
        n[..., 1] *= -1
    length = np.linalg.norm(n, axis=2, keepdims=True)
    zero = int(np.count_nonzero(length < 1e-6))
    if zero:
        raise UserError(f"{ref.path}: {zero} zero-length normals (texels at 0.5 grey); expected a normal map")
    return _read_only((n / length).astype(np.float32))


def clear_cache() -> None:
    """Forget loaded textures (after files changed on disk, or between tests)."""
    for fn in (_builtin, load_height, load_depth, load_albedo, load_normal_map):
        fn.cache_clear()
