"""The one reader of image and array files, for scenes, meshes and maptools alike.

``read_header`` (``image_headers``): format, size and channels of a file from its first bytes only, every limit
checked there: a file declaring 60000x60000 is refused at once, before any data is read.

``read_image``: an image file (8/16-bit PNG, JPEG, TIFF, ... whatever OpenCV decodes; OpenEXR through the
``openexr`` package, which reads every compression and half/float channels, while the pip OpenCV wheels read no
EXR) or a ``.npy`` array as float32 in [0, 1], RGB(A) order. An EXR's channels are one (any name: Y, Z, height),
Y and A, or R, G, B (and A); its header says which before any pixel is read, and anything else (UINT or subsampled
channels, deep data, other channel sets) is refused there. ``read_height``: a height (or depth) map from
such a file as float32 (H, W) in [0, 1], with one channel rule everywhere:

- ``auto``: a grey file as it is; a colour file whose colour channels are equal as that channel; any other colour
  file as its Rec. 709 luma (a height map is data: no sRGB decoding);
- ``grey``: the file must be grey (or colour with equal channels);
- ``r``, ``g``, ``b``, ``a``: that channel (a grey file has its value in every colour channel);
- ``luma``: Rec. 709 luma of the colour channels.

Every reader takes a path or an ``ImageBytes`` (a file's bytes in memory: an image a glTF embeds), decoded alike.
Non-finite values (float files) follow ``nan_policy``: ``error`` (refuse), ``zero``, or ``nearest`` (the value of
the nearest finite texel); how many were replaced is logged as a warning. Every problem is a one-line
``FileError`` (a ``UserError``) naming the file; its ``reason`` lets a caller name the key the file came from.
What the native decoders print is taken into that line (``native_output``).
"""

from __future__ import annotations

import logging
from pathlib import Path

import cv2
import numpy as np

from .errors import FileError, UserError
from .image_headers import (
    FORMATS,
    MAX_CHANNELS,
    MAX_SIDE,
    Header,
    ImageBytes,
    as_source,
    link_problem,
    open_source,
    read_header,
    resolve_path,
)
from .native_output import native_stderr, python_stdout

__all__ = ["HEIGHT_CHANNELS", "MAX_CHANNELS", "MAX_SIDE", "NAN_POLICIES", "Header", "ImageBytes", "fill_nonfinite",
           "link_problem", "read_header", "read_height", "read_image", "resolve_path"]

HEIGHT_CHANNELS = ("auto", "grey", "r", "g", "b", "a", "luma")
NAN_POLICIES = ("error", "zero", "nearest")
REC709 = np.array([0.2126, 0.7152, 0.0722])
_RGBA = "rgba"

log = logging.getLogger("wgpuviewer.images")


def _decode_exr(source: Path | ImageBytes, header: Header, said: list[str]) -> np.ndarray | None:
    """The channels ``header`` names (R, G, B order), stacked; None when the file cannot be decoded (why: in
    ``said``, with the decoder's own lines)."""
    import OpenEXR

    try:
        with OpenEXR.File(str(source) if isinstance(source, Path) else open_source(source),
                          separate_channels=True) as exr:
            planes = exr.channels() if exr.parts else {}
            data = [planes[name].pixels for name in header.channel_names if name in planes]
    except Exception as e:  # noqa: BLE001 - the library's exceptions for a bad file have no common type
        said.append(f"{type(e).__name__}: {e}")
        return None
    if len(data) != len(header.channel_names) or any(d is None for d in data):
        return None
    return data[0] if len(data) == 1 else np.stack(data, axis=-1)


def _decode(path: Path | ImageBytes) -> tuple[np.ndarray, bool]:
    """Raw array of a file and whether its channels are in RGB(A) order (.npy, EXR) rather than BGR(A) (OpenCV).
    The header is checked first: nothing over the limits is ever loaded."""
    header = read_header(path)
    if header.format == "npy":
        try:
            with open_source(path) as f:
                return np.load(f, allow_pickle=False), True
        except Exception as e:  # noqa: BLE001 - any parse failure is the file's fault
            raise FileError(path, f"cannot read .npy array ({type(e).__name__}: {e}); save it with numpy.save") \
                from None
    said: list[str] = []
    if header.format == "exr":
        with native_stderr(said), python_stdout(said):
            data = _decode_exr(path, header, said)
    else:
        encoded = np.frombuffer(path.data, np.uint8) if isinstance(path, ImageBytes) else np.fromfile(path, np.uint8)
        with native_stderr(said):
            # imdecode instead of imread: the same decoders, but non-ASCII paths work everywhere.
            data = cv2.imdecode(encoded, cv2.IMREAD_UNCHANGED)
    decoder = f"; the decoder said: {'; '.join(said)}" if said else ""
    if data is None:
        raise FileError(path, f"cannot decode image (corrupt or unsupported {header.format}{decoder}); "
                              f"write or download it again, or use {FORMATS}")
    if said:
        log.warning(f"{path}: decoded, but the {header.format} decoder said: {'; '.join(said)}; if the image looks "
                    "damaged, write or download it again")
    return data, header.format == "exr"


def _scaled(data: np.ndarray, path: Path) -> np.ndarray:
    """Integers divided by their maximum (255, 65535), floats as they are, as float32."""
    if data.dtype == np.uint8:
        return data.astype(np.float32) / np.float32(255)
    if data.dtype == np.uint16:
        return data.astype(np.float32) / np.float32(65535)
    if data.dtype.kind == "f":
        return data.astype(np.float32)
    raise FileError(path, f"unsupported dtype {data.dtype}; expected uint8, uint16 or float")


def _channels_last(data: np.ndarray, rgb_order: bool, path: Path) -> np.ndarray:
    """(h, w) grey, or (h, w, C) with C in 2 (grey + alpha), 3, 4 in R, G, B(, A) order."""
    if data.size == 0:
        raise FileError(path, f"empty image (shape {data.shape})")
    if data.ndim == 3 and data.shape[2] == 1:
        data = data[..., 0]
    if not (data.ndim == 2 or (data.ndim == 3 and data.shape[2] in (2, 3, 4))):
        raise FileError(path, f"unsupported shape {data.shape}; expected (h, w), (h, w, 3) or (h, w, 4)")
    if data.ndim == 3 and data.shape[2] >= 3 and not rgb_order:
        data = data[..., [2, 1, 0, 3][: data.shape[2]]]
    return data


def read_image(path, channel: str = "auto") -> np.ndarray:
    """Image file or .npy array as float32 scaled to [0, 1] (floats as they are; callers check the range).

    Returns (h, w) for grey data or a named channel ('r', 'g', 'b', 'a'), else (h, w, 3|4) in RGB(A) order
    (grey + alpha files come back as grey). Non-finite values are refused.
    """
    path = as_source(path)
    raw, rgb_order = _decode(path)
    data = _scaled(_channels_last(raw, rgb_order, path), path)
    bad = int(np.count_nonzero(~np.isfinite(data)))
    if bad:
        raise FileError(path, f"{bad} non-finite values (NaN/inf); clean the data or replace non-finite values")
    if data.ndim == 3 and data.shape[2] == 2:
        data = data[..., 0] if channel != "a" else data[..., 1]
        return data
    if channel == "auto":
        return data
    if channel not in _RGBA:
        raise FileError(path, f"channel {channel!r}: unknown; expected auto, r, g, b or a")
    present = _RGBA[: data.shape[2]] if data.ndim == 3 else ""
    if channel not in present:
        kind = f"{data.shape[2]}-channel" if present else "greyscale"
        raise FileError(path, f"channel {channel!r} requested but the image is {kind}; use channel 'auto'"
                        + (f" or one of {', '.join(present)}" if present else ""))
    return data[..., present.index(channel)]


def fill_nonfinite(a: np.ndarray, policy: str, path) -> np.ndarray:
    """Replace NaN/inf texels: error (refuse), zero, or nearest (value of the nearest finite texel, L2). How many
    were replaced is logged as a warning naming ``path``."""
    if policy not in NAN_POLICIES:
        raise UserError(f"--nan-policy {policy!r}: expected one of {', '.join(NAN_POLICIES)}")
    bad = ~np.isfinite(a)
    count = int(np.count_nonzero(bad))
    if not count:
        return a
    if policy == "error":
        raise FileError(path, f"{count} non-finite values (NaN/inf); clean the data "
                              "(maptools: --nan-policy zero|nearest replaces them)")
    if count == a.size:
        raise FileError(path, "every texel is NaN/inf; nothing to fill from")
    a = a.copy()
    if policy == "zero":
        a[bad] = 0.0
    else:
        # Each finite texel is a zero pixel with its own label (row-major order); every other texel gets the label
        # of its nearest zero pixel.
        _, labels = cv2.distanceTransformWithLabels(bad.astype(np.uint8), cv2.DIST_L2, 5,
                                                    labelType=cv2.DIST_LABEL_PIXEL)
        a[bad] = a[~bad][labels[bad] - 1]
    log.warning(f"{path}: {count} of {a.size} texels were NaN/inf; replaced ({policy}: "
                f"{'0' if policy == 'zero' else 'the nearest finite value'})")
    return a


def _height_channel(data: np.ndarray, channel: str, path: Path) -> np.ndarray:
    if data.ndim == 2:
        if channel == "a":
            raise FileError(path, "channel 'a' requested but the image is greyscale; use channel 'auto'")
        return data
    if data.shape[2] == 2:  # grey + alpha
        return data[..., 1] if channel == "a" else data[..., 0]
    rgb = data[..., :3]
    if channel == "a":
        if data.shape[2] < 4:
            raise FileError(path, "channel 'a' requested but the image is 3-channel (no alpha); "
                                  "use channel 'auto' or one of r, g, b")
        return data[..., 3]
    if channel in ("r", "g", "b"):
        return rgb[..., "rgb".index(channel)]
    equal = np.array_equal(rgb[..., 0], rgb[..., 1]) and np.array_equal(rgb[..., 0], rgb[..., 2])
    if channel == "grey" and not equal:
        raise FileError(path, "colour image with different channels; choose channel r|g|b|a|luma")
    if equal and channel != "luma":
        return rgb[..., 0]
    return (rgb.astype(np.float64) @ REC709).astype(np.float32)


def read_height(path, channel: str = "auto", nan_policy: str = "error", *, is_depth: bool = False) -> np.ndarray:
    """Height (h, w) float32 in [0, 1], 1 = top, from a file (module docstring: channels, NaN policies).

    ``is_depth``: the file holds depth (0 = top); it is returned as height 1 - depth.
    """
    path = as_source(path)
    if channel not in HEIGHT_CHANNELS:
        raise FileError(path, f"channel {channel!r}: unknown; expected one of {', '.join(HEIGHT_CHANNELS)}")
    if nan_policy not in NAN_POLICIES:
        raise UserError(f"--nan-policy {nan_policy!r}: expected one of {', '.join(NAN_POLICIES)}")
    raw, rgb_order = _decode(path)
    if raw.dtype == bool or raw.dtype.kind not in "uif":
        raise FileError(path, f"unsupported dtype {raw.dtype}; expected uint8, uint16 or float")
    data = _height_channel(_scaled(_channels_last(raw, rgb_order, path), path), channel, path)
    data = fill_nonfinite(np.ascontiguousarray(data, np.float32), nan_policy, path)
    lo, hi = float(data.min()), float(data.max())
    if lo < 0 or hi > 1:
        what = "depth" if is_depth else "height"
        raise FileError(path, f"{what} values range from {lo:g} to {hi:g}; expected [0, 1] (normalise the data)")
    return (1 - data if is_depth else data).astype(np.float32, copy=False)
