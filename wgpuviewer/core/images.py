"""The one reader of image and array files, for scenes and maptools alike.

``read_header``: format, size and channels of a file from its first bytes only (``.npy`` header, PNG, JPEG, EXR,
and whatever else Pillow identifies), with every limit checked there: a file declaring 60000x60000 is refused at
once, before any data is read. Empty, truncated, missing and directory inputs are refused there too.

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

Non-finite values (float files) follow ``nan_policy``: ``error`` (refuse), ``zero``, or ``nearest`` (the value of
the nearest finite texel); how many were replaced is logged as a warning. Every problem is a one-line
``FileError`` (a ``UserError``) naming the file; its ``reason`` lets a caller name the key the file came from.
A broken symbolic link or a link loop is named as such (``link_problem``), not as a missing or unreadable file.

The native decoders (libpng, libjpeg, OpenEXR) print their complaints on the process's stderr themselves (the
``openexr`` module also through Python's stdout); those lines are captured around each decode (``_native_stderr``,
``_python_stdout``) and end up in our one line: the reason of a decode that failed, or a warning naming the file
when the decoder recovered (a damaged JPEG decodes with garbage in it).
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
import struct
import sys
import tempfile
import threading
from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np

from .errors import FileError, UserError

HEIGHT_CHANNELS = ("auto", "grey", "r", "g", "b", "a", "luma")
NAN_POLICIES = ("error", "zero", "nearest")
REC709 = np.array([0.2126, 0.7152, 0.0722])
_RGBA = "rgba"

#: Largest side of any image or array read (the WebGPU default 2D texture limit; builtins have the same).
MAX_SIDE = 8192
#: Most channels per texel.
MAX_CHANNELS = 4

log = logging.getLogger("wgpuviewer.images")

_NPY_MAGIC = b"\x93NUMPY"
_EXR_MAGIC = b"\x76\x2f\x31\x01"
_PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
_JPEG_MAGIC = b"\xff\xd8\xff"
_FORMATS = "PNG, JPEG, EXR or .npy"
_REWRITE = "write or download it again"


@dataclass(frozen=True)
class Header:
    """What a file's first bytes say: ``format`` (npy, png, jpeg, exr or Pillow's name), ``width``, ``height``,
    ``channels`` (0 where the header does not say), ``channel_names`` (EXR: the channels in the order they are
    read, e.g. R, G, B)."""

    format: str
    width: int
    height: int
    channels: int = 0
    channel_names: tuple[str, ...] = ()


def _npy_header(path: Path, f, size: int) -> Header:
    try:
        version = np.lib.format.read_magic(f)
        read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, _fortran, dtype = read(f)
    except Exception as e:  # noqa: BLE001 - any parse failure is the file's fault
        raise FileError(path, f"cannot read .npy array (bad header: {e}); save it with numpy.save") from None
    if dtype.hasobject or dtype.kind not in "uif":
        raise FileError(path, f"unsupported dtype {dtype}; expected uint8, uint16 or float")
    if len(shape) not in (2, 3) or (len(shape) == 3 and not 1 <= shape[2] <= MAX_CHANNELS):
        raise FileError(path, f"unsupported shape {shape}; expected (h, w), (h, w, 3) or (h, w, 4)")
    need = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
    header = Header("npy", int(shape[1]), int(shape[0]), int(shape[2]) if len(shape) == 3 else 1)
    _check_limits(path, header, shape)
    have = size - f.tell()
    if have < need:
        raise FileError(path, f"truncated: the header declares {shape} {dtype} ({need} bytes of data) but only "
                              f"{have} follow; save it again with numpy.save")
    return header


#: OpenEXR's version-field flags (the 4 bytes after the magic number): non-image (deep) data.
_EXR_DEEP = 0x800
#: OpenEXR pixel types in a channel list.
_EXR_PIXEL_TYPES = {0: "UINT", 1: "HALF", 2: "FLOAT"}


@dataclass(frozen=True)
class _ExrChannel:
    name: str
    pixel_type: int
    sampling: tuple[int, int]


def _exr_channels(value: bytes) -> list[_ExrChannel]:
    """An EXR ``chlist`` attribute: per channel its name, NUL, pixel type (int32), pLinear and 3 reserved bytes,
    x and y sampling (int32); a NUL ends the list."""
    channels, at = [], 0
    while at < len(value) and value[at]:
        end = value.index(b"\0", at)
        pixel_type, _linear, x, y = struct.unpack_from("<iB3xii", value, end + 1)
        channels.append(_ExrChannel(value[at:end].decode(errors="replace"), pixel_type, (x, y)))
        at = end + 17
    return channels


def _exr_order(path: Path, channels: list[_ExrChannel]) -> list[str]:
    """The channels of an EXR in the order they are read: one channel (grey, any name), Y and A (grey + alpha),
    or R, G, B (and A); each HALF or FLOAT at full resolution."""
    names = [c.name for c in channels]
    shown = ", ".join(names) or "none"
    for c in channels:
        if c.pixel_type not in (1, 2):
            kind = _EXR_PIXEL_TYPES.get(c.pixel_type, f"type {c.pixel_type}")
            raise FileError(path, f"EXR channel {c.name!r} holds {kind} values; expected HALF or FLOAT (save the "
                                  "height as a float channel)")
        if c.sampling != (1, 1):
            raise FileError(path, f"EXR channel {c.name!r} is subsampled {c.sampling[0]}x{c.sampling[1]}; expected "
                                  "full resolution")
    by_upper = {n.upper(): n for n in names}
    for order in (["R", "G", "B", "A"], ["R", "G", "B"], ["Y", "A"]):
        if len(names) == len(order) and set(by_upper) == set(order):
            return [by_upper[n] for n in order]
    if len(names) == 1:
        return names
    raise FileError(path, f"EXR channels {shown}: expected one channel (the height), Y and A, or R, G, B (and A); "
                          "save the height as its own file")


def _exr_header(path: Path, f) -> Header:
    """OpenEXR: after magic and version, attributes (name, type, size, value); ``dataWindow`` (box2i) is the size,
    ``channels`` (chlist) what is stored (``_exr_order``: the channel names in the order they are read). A
    multi-part file's first header is its first part's, which is the part read."""
    (version,) = struct.unpack("<i", f.read(8)[4:].ljust(4, b"\0"))
    window, channels, deep = None, None, bool(version & _EXR_DEEP)
    for _ in range(1024):
        name = _cstring(f)
        if not name:
            break
        kind, (length,) = _cstring(f), struct.unpack("<i", f.read(4).ljust(4, b"\0"))
        value = f.read(max(length, 0))
        if len(value) < length:
            break
        if name == b"dataWindow" and kind == b"box2i" and length == 16:
            window = struct.unpack("<4i", value)
        elif name == b"channels" and kind == b"chlist":
            try:
                channels = _exr_channels(value)
            except (ValueError, struct.error):
                raise FileError(path, f"damaged EXR header (its channel list); {_REWRITE}") from None
        elif name == b"type" and kind == b"string":
            deep = deep or value.startswith(b"deep")
    if window is None or channels is None:
        missing = "dataWindow" if window is None else "channels"
        raise FileError(path, f"cannot read the EXR header (no {missing}); {_REWRITE}")
    xmin, ymin, xmax, ymax = window
    header = Header("exr", xmax - xmin + 1, ymax - ymin + 1, len(channels))
    _check_limits(path, header)
    if deep:
        raise FileError(path, "deep EXR data (several samples per pixel); save a flat scanline or tiled image")
    return replace(header, channel_names=tuple(_exr_order(path, channels)))


def _cstring(f) -> bytes:
    out = bytearray()
    while len(out) < 256:
        c = f.read(1)
        if not c or c == b"\0":
            break
        out += c
    return bytes(out)


_PIL_LOCK = threading.Lock()


def _pil_header(path: Path) -> Header:
    """Pillow reads only the header on ``open``; its own size guard is off here (our limits come after)."""
    from PIL import Image, UnidentifiedImageError

    with _PIL_LOCK:
        guard, Image.MAX_IMAGE_PIXELS = Image.MAX_IMAGE_PIXELS, None
        try:
            with Image.open(path) as image:
                (w, h), mode, fmt = image.size, image.mode, (image.format or "image").lower()
        except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as e:
            what = "unrecognised contents" if isinstance(e, UnidentifiedImageError) else f"bad header: {e}"
            raise FileError(path, f"cannot decode image ({what}); use {_FORMATS}") from None
        finally:
            Image.MAX_IMAGE_PIXELS = guard
    return Header(fmt, w, h, Image.getmodebands(mode) if mode in Image.MODES else 0)


def _check_limits(path: Path, header: Header, shape=None) -> None:
    if header.width <= 0 or header.height <= 0:
        raise FileError(path, f"empty image (shape {shape if shape is not None else (header.height, header.width)})")
    if max(header.width, header.height) > MAX_SIDE:
        raise FileError(path, f"{header.width}x{header.height} is larger than the limit of {MAX_SIDE} texels per "
                              "side; downscale it")


def _check_tail(path: Path, f, size: int, fmt: str) -> None:
    """PNG ends with its IEND chunk, JPEG with its end-of-image marker; a cut file does not."""
    f.seek(max(size - 1024, 0))
    tail = f.read()
    if fmt == "png" and b"IEND" not in tail:
        raise FileError(path, f"truncated PNG (no IEND chunk at the end); {_REWRITE}")
    if fmt == "jpeg" and b"\xff\xd9" not in tail:
        raise FileError(path, f"truncated JPEG (no end-of-image marker); {_REWRITE}")


def link_problem(path) -> str | None:
    """Why the symbolic link ``path`` leads to no file: a broken link (its target does not exist) or a link loop,
    with the fix; None when ``path`` is not such a link."""
    try:
        os.stat(path)
    except FileNotFoundError:
        if os.path.islink(path):
            return f"broken link to {os.readlink(path)} (the target does not exist); fix or remove the link"
    except OSError as e:
        if e.errno == errno.ELOOP:
            return "symbolic link loop (the link leads back to itself); fix or remove the link"
    return None


def read_header(path) -> Header:
    """Format and size of an image or ``.npy`` file from its header, every limit checked (module docstring)."""
    path = Path(path)
    try:
        f = open(path, "rb")  # noqa: SIM115 - closed below
    except FileNotFoundError:
        raise FileError(path, link_problem(path) or "file not found") from None
    except IsADirectoryError:
        raise FileError(path, f"is a directory; expected an image or .npy file ({_FORMATS})") from None
    except OSError as e:
        raise FileError(path, link_problem(path) or f"cannot read ({e.strerror or e})") from None
    with f:
        if not os.path.isfile(path):
            raise FileError(path, f"not a regular file; expected an image or .npy file ({_FORMATS})")
        size = os.fstat(f.fileno()).st_size
        if size == 0:
            raise FileError(path, f"empty file (0 bytes); expected an image or .npy file ({_FORMATS})")
        magic = f.read(8)
        f.seek(0)
        if magic.startswith(_NPY_MAGIC):
            return _npy_header(path, f, size)
        if path.suffix.lower() == ".npy":
            raise FileError(path, "cannot read .npy array (no .npy header); save it with numpy.save")
        if magic.startswith(_EXR_MAGIC):
            return _exr_header(path, f)
        known = "png" if magic.startswith(_PNG_MAGIC) else "jpeg" if magic.startswith(_JPEG_MAGIC) else ""
        try:
            header = _pil_header(path)
        except FileError:
            if known:  # the signature is there, the rest is not
                raise FileError(path, f"damaged or truncated {known.upper()} header; write or download it again") \
                    from None
            raise
        _check_limits(path, header)
        if header.channels > MAX_CHANNELS:
            raise FileError(path, f"{header.channels} channels; expected at most {MAX_CHANNELS}")
        if known:
            _check_tail(path, f, size, known)
        return header


_NATIVE_STDERR_LOCK = threading.Lock()


def _writes_to_fd2(stream) -> bool:
    try:
        return stream.fileno() == 2
    except (AttributeError, OSError, ValueError):  # pytest's capture, a closed or replaced stream
        return False


class _HeldStderr:
    """Stands in for ``sys.stderr`` while a decode holds file descriptor 2: other threads' writes wait for the
    decode to end and then go to the stream that was there, so none is taken for the decoder's. Whoever keeps a
    reference past the decode writes straight through."""

    def __init__(self, stream, released: threading.Event):
        self._stream, self._released, self._owner = stream, released, threading.get_ident()

    def write(self, text):
        if threading.get_ident() != self._owner:
            self._released.wait()
        return self._stream.write(text)

    def __getattr__(self, name):  # flush, fileno, isatty, encoding, ...
        return getattr(self._stream, name)


@contextlib.contextmanager
def _native_stderr(messages: list[str]):
    """Appends to ``messages`` the lines native code prints on file descriptor 2 during the block, instead of
    letting them reach the terminal ahead of our own line. One block at a time holds the descriptor; Python's
    stderr is held meanwhile (``_HeldStderr``), and terminal redraws written to the descriptor (a progress bar:
    lines with CR or escape codes) are passed on."""
    with _NATIVE_STDERR_LOCK, tempfile.TemporaryFile() as sink:
        python_stderr = sys.stderr
        with contextlib.suppress(Exception):
            python_stderr.flush()
        try:
            saved = os.dup(2)
        except OSError:  # no descriptor 2 (a detached process): nothing to take
            yield
            return
        released = threading.Event()
        held = _HeldStderr(python_stderr, released) if _writes_to_fd2(python_stderr) else None
        if held is not None:
            sys.stderr = held
        os.dup2(sink.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            released.set()
            if held is not None and sys.stderr is held:
                sys.stderr = python_stderr
            sink.seek(0)
            lines = sink.read().decode(errors="replace").split("\n")
            for i, line in enumerate(lines):
                if "\r" in line or "\x1b" in line:
                    with contextlib.suppress(Exception):
                        python_stderr.write(line + ("\n" if i < len(lines) - 1 else ""))
                        python_stderr.flush()
                elif line.strip():
                    messages.append(line.strip())


class _CapturedStdout:
    """Stands in for ``sys.stdout`` while the ``openexr`` module decodes: what the decoding thread prints (the
    module's warnings) is kept; other threads write to the stream that was there."""

    def __init__(self, stream):
        self._stream, self._owner, self.text = stream, threading.get_ident(), []

    def write(self, text):
        if threading.get_ident() != self._owner:
            return self._stream.write(text)
        self.text.append(text)
        return len(text)

    def __getattr__(self, name):  # flush, fileno, isatty, encoding, ...
        return getattr(self._stream, name)


@contextlib.contextmanager
def _python_stdout(messages: list[str]):
    """Appends to ``messages`` the lines this thread prints through Python's stdout during the block."""
    captured = _CapturedStdout(sys.stdout)
    sys.stdout = captured
    try:
        yield
    finally:
        if sys.stdout is captured:
            sys.stdout = captured._stream
        messages.extend(line.strip() for line in "".join(captured.text).splitlines() if line.strip())


def _decode_exr(path: Path, header: Header, said: list[str]) -> np.ndarray | None:
    """The channels ``header`` names (R, G, B order), stacked; None when the file cannot be decoded (why: in
    ``said``, with the decoder's own lines)."""
    import OpenEXR

    try:
        with OpenEXR.File(str(path), separate_channels=True) as exr:
            planes = exr.channels() if exr.parts else {}
            data = [planes[name].pixels for name in header.channel_names if name in planes]
    except Exception as e:  # noqa: BLE001 - the library's exceptions for a bad file have no common type
        said.append(f"{type(e).__name__}: {e}")
        return None
    if len(data) != len(header.channel_names) or any(d is None for d in data):
        return None
    return data[0] if len(data) == 1 else np.stack(data, axis=-1)


def _decode(path: Path) -> tuple[np.ndarray, bool]:
    """Raw array of a file and whether its channels are in RGB(A) order (.npy, EXR) rather than BGR(A) (OpenCV).
    The header is checked first: nothing over the limits is ever loaded."""
    header = read_header(path)
    if header.format == "npy":
        try:
            return np.load(path, allow_pickle=False), True
        except Exception as e:  # noqa: BLE001 - any parse failure is the file's fault
            raise FileError(path, f"cannot read .npy array ({type(e).__name__}: {e}); save it with numpy.save") \
                from None
    said: list[str] = []
    if header.format == "exr":
        with _native_stderr(said), _python_stdout(said):
            data = _decode_exr(path, header, said)
    else:
        encoded = np.fromfile(path, np.uint8)
        with _native_stderr(said):
            # imdecode instead of imread: the same decoders, but non-ASCII paths work everywhere.
            data = cv2.imdecode(encoded, cv2.IMREAD_UNCHANGED)
    decoder = f"; the decoder said: {'; '.join(said)}" if said else ""
    if data is None:
        raise FileError(path, f"cannot decode image (corrupt or unsupported {header.format}{decoder}); "
                              f"write or download it again, or use {_FORMATS}")
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
    path = Path(path)
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
    path = Path(path)
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
