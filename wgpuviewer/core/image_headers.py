"""Image headers: format, size and channels of an image or ``.npy`` file from its first bytes only, with every limit
checked there (``read_header``): a file declaring 60000x60000 is refused at once, before any data is read. Empty,
truncated, missing and directory inputs are refused there too; a broken symbolic link or a link loop is named as
such (``link_problem``), and ``resolve_path`` makes any input path absolute with a link loop one FileError.

A source is a path or an ``ImageBytes`` (an image file's bytes held in memory, such as one a glTF embeds): both are
read alike, the bytes without a temporary file. Headers: ``.npy`` through numpy's header reader, EXR through the
``openexr`` package's own header reading (its channel list, data window and storage type), PNG, JPEG and the rest
through Pillow (which reads only the header on ``open``).
"""

from __future__ import annotations

import errno
import io
import os
import threading
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import FileError
from .native_output import native_stderr, python_stdout

#: Largest side of any image or array read (the WebGPU default 2D texture limit; builtins have the same).
MAX_SIDE = 8192
#: Most channels per texel.
MAX_CHANNELS = 4

_NPY_MAGIC = b"\x93NUMPY"
_EXR_MAGIC = b"\x76\x2f\x31\x01"
_PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
_JPEG_MAGIC = b"\xff\xd8\xff"
FORMATS = "PNG, JPEG, EXR or .npy"
REWRITE = "write or download it again"


@dataclass(frozen=True)
class ImageBytes:
    """An image file's bytes held in memory, read like a file by every reader of ``core.images``; ``name`` stands
    for the path in messages (``scene.glb: images[0]``)."""

    name: str
    data: bytes = field(repr=False)
    suffix = ""

    def __str__(self) -> str:
        return self.name


def as_source(source) -> Path | ImageBytes:
    """``source`` as the readers take it: ImageBytes as they are, bare bytes as ImageBytes named ``<image bytes>``,
    anything else as a Path."""
    if isinstance(source, bytes | bytearray | memoryview):
        return ImageBytes("<image bytes>", bytes(source))
    return source if isinstance(source, ImageBytes) else Path(source)


def open_source(source: Path | ImageBytes):
    """A binary stream of the source's bytes: OpenEXR, Pillow and numpy read it like a file."""
    return io.BytesIO(source.data) if isinstance(source, ImageBytes) else open(source, "rb")  # noqa: SIM115


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


def _npy_header(path, f, size: int) -> Header:
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


def _exr_order(path, channels: dict) -> list[str]:
    """The channels of an EXR (name -> (pixel type name, x and y sampling)) in the order they are read: one
    channel (grey, any name), Y and A (grey + alpha), or R, G, B (and A); each HALF or FLOAT at full resolution."""
    names = list(channels)
    shown = ", ".join(sorted(names, key=lambda n: ("RGBA".find(n.upper()) % 5 if len(n) == 1 else 4, n))) or "none"
    for name, (kind, sampling) in channels.items():
        if kind not in ("HALF", "FLOAT"):
            raise FileError(path, f"EXR channel {name!r} holds {kind} values; expected HALF or FLOAT (save the "
                                  "height as a float channel)")
        if sampling != (1, 1):
            raise FileError(path, f"EXR channel {name!r} is subsampled {sampling[0]}x{sampling[1]}; expected "
                                  "full resolution")
    by_upper = {n.upper(): n for n in names}
    for order in (["R", "G", "B", "A"], ["R", "G", "B"], ["Y", "A"]):
        if len(names) == len(order) and set(by_upper) == set(order):
            return [by_upper[n] for n in order]
    if len(names) == 1:
        return names
    raise FileError(path, f"EXR channels {shown}: expected one channel (the height), Y and A, or R, G, B (and A); "
                          "save the height as its own file")


def _exr_attributes(source: Path | ImageBytes) -> tuple[dict, dict]:
    """(first part's header, channel name -> (pixel type name, sampling)) through the openexr package's own header
    reading: ``File(header_only=True)`` for the part (data window, storage type), the ``InputFile`` header for the
    channels' pixel types (a header-only File does not keep them). Deep parts are answered by the first alone."""
    import OpenEXR

    said: list[str] = []
    try:
        with native_stderr(said), python_stdout(said), open_source(source) as f:
            with OpenEXR.File(f, header_only=True) as exr:
                header = dict(exr.parts[0].header)
            if header.get("type") in (OpenEXR.deepscanline, OpenEXR.deeptile):
                return header, {}
            f.seek(0)
            described = OpenEXR.InputFile(f).header()["channels"]
    except Exception as e:  # noqa: BLE001 - the library's exceptions for a bad file have no common type
        said.append(f"{type(e).__name__}: {e}")
        raise FileError(source, f"damaged EXR header ({'; '.join(said)}); {REWRITE}") from None
    channels = {name: (str(c.type), (c.xSampling, c.ySampling)) for name, c in sorted(described.items())}
    return header, channels


def _exr_header(source: Path | ImageBytes) -> Header:
    """OpenEXR: the size from the first part's ``dataWindow``, what is stored from its ``channels``
    (``_exr_order``: the channel names in the order they are read). A multi-part file's first part is the part
    read."""
    import OpenEXR

    attributes, channels = _exr_attributes(source)
    if "dataWindow" not in attributes:
        raise FileError(source, f"cannot read the EXR header (no dataWindow); {REWRITE}")
    low, high = (np.asarray(corner, np.int64) for corner in attributes["dataWindow"])
    header = Header("exr", int(high[0] - low[0] + 1), int(high[1] - low[1] + 1), len(channels))
    _check_limits(source, header)
    if attributes.get("type") in (OpenEXR.deepscanline, OpenEXR.deeptile):
        raise FileError(source, "deep EXR data (several samples per pixel); save a flat scanline or tiled image")
    return Header("exr", header.width, header.height, len(channels), tuple(_exr_order(source, channels)))


_PIL_LOCK = threading.Lock()


def _pil_header(source: Path | ImageBytes) -> Header:
    """Pillow reads only the header on ``open``; its own size guard is off here (our limits come after)."""
    from PIL import Image, UnidentifiedImageError

    with _PIL_LOCK:
        guard, Image.MAX_IMAGE_PIXELS = Image.MAX_IMAGE_PIXELS, None
        try:
            with Image.open(io.BytesIO(source.data) if isinstance(source, ImageBytes) else source) as image:
                (w, h), mode, fmt = image.size, image.mode, (image.format or "image").lower()
        except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as e:
            what = "unrecognised contents" if isinstance(e, UnidentifiedImageError) else f"bad header: {e}"
            raise FileError(source, f"cannot decode image ({what}); use {FORMATS}") from None
        finally:
            Image.MAX_IMAGE_PIXELS = guard
    return Header(fmt, w, h, Image.getmodebands(mode) if mode in Image.MODES else 0)


def _check_limits(path, header: Header, shape=None) -> None:
    if header.width <= 0 or header.height <= 0:
        raise FileError(path, f"empty image (shape {shape if shape is not None else (header.height, header.width)})")
    if max(header.width, header.height) > MAX_SIDE:
        raise FileError(path, f"{header.width}x{header.height} is larger than the limit of {MAX_SIDE} texels per "
                              "side; downscale it")


def _check_tail(path, f, size: int, fmt: str) -> None:
    """PNG ends with its IEND chunk, JPEG with its end-of-image marker; a cut file does not."""
    f.seek(max(size - 1024, 0))
    tail = f.read()
    if fmt == "png" and b"IEND" not in tail:
        raise FileError(path, f"truncated PNG (no IEND chunk at the end); {REWRITE}")
    if fmt == "jpeg" and b"\xff\xd9" not in tail:
        raise FileError(path, f"truncated JPEG (no end-of-image marker); {REWRITE}")


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


def resolve_path(path) -> Path:
    """``path`` made absolute with its links followed (``Path.resolve``); a symbolic link loop on the way is a
    FileError naming it (``resolve`` itself raises RuntimeError or OSError there, which would be an internal error)."""
    try:
        return Path(path).resolve()
    except (RuntimeError, OSError) as e:
        raise FileError(path, link_problem(path) or f"symbolic link loop on its path ({e}); fix or remove the link") from None


def read_header(source) -> Header:
    """Format and size of an image or ``.npy`` file (a path or ImageBytes) from its header, every limit checked
    (module docstring)."""
    source = as_source(source)
    if isinstance(source, ImageBytes):
        return _header_of(source, io.BytesIO(source.data), len(source.data))
    path = source
    try:
        f = open(path, "rb")  # noqa: SIM115 - closed below
    except FileNotFoundError:
        raise FileError(path, link_problem(path) or "file not found") from None
    except IsADirectoryError:
        raise FileError(path, f"is a directory; expected an image or .npy file ({FORMATS})") from None
    except OSError as e:
        raise FileError(path, link_problem(path) or f"cannot read ({e.strerror or e})") from None
    with f:
        if not os.path.isfile(path):
            raise FileError(path, f"not a regular file; expected an image or .npy file ({FORMATS})")
        return _header_of(path, f, os.fstat(f.fileno()).st_size)


def _header_of(source: Path | ImageBytes, f, size: int) -> Header:
    """The header of ``source``, open as ``f`` (``size`` bytes)."""
    if size == 0:
        raise FileError(source, f"empty file (0 bytes); expected an image or .npy file ({FORMATS})")
    magic = f.read(8)
    f.seek(0)
    if magic.startswith(_NPY_MAGIC):
        return _npy_header(source, f, size)
    if source.suffix.lower() == ".npy":
        raise FileError(source, "cannot read .npy array (no .npy header); save it with numpy.save")
    if magic.startswith(_EXR_MAGIC):
        return _exr_header(source)
    known = "png" if magic.startswith(_PNG_MAGIC) else "jpeg" if magic.startswith(_JPEG_MAGIC) else ""
    try:
        header = _pil_header(source)
    except FileError:
        if known:  # the signature is there, the rest is not
            raise FileError(source, f"damaged or truncated {known.upper()} header; {REWRITE}") from None
        raise
    _check_limits(source, header)
    if header.channels > MAX_CHANNELS:
        raise FileError(source, f"{header.channels} channels; expected at most {MAX_CHANNELS}")
    if known:
        _check_tail(source, f, size, known)
    return header
