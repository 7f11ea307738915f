"""A glTF document's buffers, buffer views and accessors, read with every number checked first.

A hostile file's numbers never reach a slice, an allocation or ``as_strided`` unchecked: a buffer's byteLength is
checked against what holds it (an external ``.bin`` is checked against its size and only its declared bytes are
read; a data URI and the GLB chunk against their lengths); a view's byteOffset and byteLength against its buffer; an
accessor's count against ``MAX_MESH_VERTICES`` before anything of that size is made, its byteOffset, its view's
byteStride (from the element size to 252) and the last element's end against its view. ``_rows`` checks the bounds
once more before it makes the strided view.
"""

from __future__ import annotations

import base64
import binascii
from pathlib import Path
from urllib.parse import unquote

import numpy as np

from wgpuviewer.core.errors import FileError
from wgpuviewer.core.images import resolve_path

from . import model
from .gltf_document import Document

_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_TYPE_SIZES = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
#: Index accessors' component types: unsigned byte, short, int.
INDEX_TYPES = (5121, 5123, 5125)
#: The largest byteStride the spec allows.
MAX_STRIDE = 252


class Accessors:
    """Reads a document's buffers (once each), views and accessors; problems are FileErrors naming the key."""

    def __init__(self, doc: Document):
        self.doc, self.path = doc, doc.path
        self._buffers: dict[int, memoryview] = {}

    def fail(self, reason: str):
        raise FileError(self.path, reason)

    def external_file(self, uri: str, what: str) -> Path:
        """The file a (non-data) URI names, next to the glTF file; it must exist."""
        try:
            file = resolve_path(self.path.parent / unquote(uri))
        except FileError as error:
            self.fail(f"{what}: file {uri!r}: {error.reason}")
        if not file.is_file():
            self.fail(f"{what}: file {uri!r} not found (looked for {file})")
        return file

    def data_uri(self, uri: str, what: str) -> bytes:
        head, _, payload = uri.partition(",")
        if not head.endswith(";base64"):
            self.fail(f"{what}: a data URI without base64; expected base64 data")
        try:
            return base64.b64decode(payload)
        except (binascii.Error, ValueError) as error:
            self.fail(f"{what}: its data URI is not valid base64 ({error}); re-export it")

    def buffer(self, index) -> memoryview:
        """Buffer ``index``: exactly its byteLength bytes, checked against what holds them."""
        if index in self._buffers:
            return self._buffers[index]
        spec = self.doc.item("buffers", index)
        what, declared = f"buffers[{index}]", spec.byteLength
        if not 0 <= declared <= model.MAX_MESH_FILE_BYTES:
            self.fail(f"{what}.byteLength = {declared}: expected 0 to {model.MAX_MESH_FILE_BYTES}; re-export it")
        if spec.uri is None:
            if index != 0 or self.doc.binary is None:
                self.fail(f"{what} has no data (no uri, no GLB binary chunk)")
            data = self.doc.binary
        elif spec.uri.startswith("data:"):
            data = self.data_uri(spec.uri, what)
        else:
            data = self._read_external(self.external_file(spec.uri, what), declared, what)
        if len(data) < declared:
            self.fail(f"{what}: {len(data)} bytes, fewer than its byteLength {declared}; the file is truncated")
        self._buffers[index] = memoryview(data)[:declared]
        return self._buffers[index]

    def _read_external(self, file: Path, declared: int, what: str) -> bytes:
        """The first ``declared`` bytes of an external buffer file (its size checked first: a file far larger than
        declared is not read whole)."""
        size = file.stat().st_size
        if size < declared:
            self.fail(f"{what}: {size} bytes, fewer than its byteLength {declared}; the file is truncated")
        with open(file, "rb") as f:
            return f.read(declared)

    def view(self, index) -> tuple[memoryview, int | None]:
        """Buffer view ``index``'s bytes and its byteStride (None: tightly packed), offset and length checked."""
        view = self.doc.item("bufferViews", index)
        what = f"bufferViews[{index}]"
        start, length = view.byteOffset or 0, view.byteLength
        if start < 0 or length < 0:
            key, value = ("byteOffset", start) if start < 0 else ("byteLength", length)
            self.fail(f"{what}.{key} = {value}: expected 0 or more; re-export it")
        data = self.buffer(view.buffer)
        if start + length > len(data):
            self.fail(f"{what} reads past the end of its buffer (byteOffset {start} + byteLength {length} > "
                      f"{len(data)} bytes of buffers[{view.buffer}]); re-export it")
        return data[start:start + length], view.byteStride

    def count(self, index, limit: bool = True) -> int:
        """Accessor ``index``'s count, 0 or more and (``limit``) within the vertex limit."""
        spec = self.doc.item("accessors", index)
        what = f"accessors[{index}]"
        if spec.count < 0:
            self.fail(f"{what}.count = {spec.count}: expected 0 or more; re-export it")
        if limit and spec.count > model.MAX_MESH_VERTICES:  # before anything of that size is made
            self.fail(f"{what} has {spec.count} elements, more than the {model.MAX_MESH_VERTICES} vertices a mesh may "
                      "have; decimate it or split it into nodes")
        return spec.count

    def accessor(self, index, indices: bool = False) -> np.ndarray:
        """Accessor ``index`` as float64 (count, components), or int64 (count,) for integer scalars (``indices``:
        must be unsigned integers); normalized integers scaled to [0, 1] or [-1, 1] as glTF defines them."""
        spec = self.doc.item("accessors", index)
        what = f"accessors[{index}]"
        if spec.sparse is not None:
            self.fail(f"{what} is sparse, which is not supported; re-export without sparse accessors")
        dtype, width = _COMPONENTS.get(spec.componentType), _TYPE_SIZES.get(spec.type)
        if dtype is None or width is None:
            self.fail(f"{what}: componentType {spec.componentType} / type {spec.type} is not a glTF 2.0 accessor type; "
                      "re-export it")
        if indices and (spec.componentType not in INDEX_TYPES or width != 1):
            self.fail(f"{what} holds triangle indices as {spec.type} of componentType {spec.componentType}; expected "
                      "SCALAR unsigned integers (5121, 5123, 5125); re-export it")
        count, item = self.count(index), np.dtype(dtype).itemsize * width
        if spec.bufferView is None:
            data = np.zeros((count, width), dtype)
        else:
            data = self._read(spec, what, count, item).view(np.dtype(dtype).newbyteorder("<")).reshape(count, width)
        if spec.normalized and np.issubdtype(dtype, np.integer):
            return np.maximum(data / np.iinfo(dtype).max, -1.0)
        if spec.type == "SCALAR" and np.issubdtype(dtype, np.integer):
            return data.reshape(-1).astype(np.int64)
        return data.astype(np.float64)

    def _read(self, spec, what: str, count: int, item: int) -> np.ndarray:
        """(count, item) bytes of an accessor from its view, its offset and the view's stride checked."""
        offset = spec.byteOffset or 0
        if offset < 0:
            self.fail(f"{what}.byteOffset = {offset}: expected 0 or more; re-export it")
        raw, stride = self.view(spec.bufferView)
        if stride is not None and not item <= stride <= MAX_STRIDE:
            self.fail(f"bufferViews[{spec.bufferView}].byteStride = {stride}: expected {item} to {MAX_STRIDE} (at least "
                      f"the {item}-byte elements of {what}); re-export it")
        stride = stride or item
        if count and offset + stride * (count - 1) + item > len(raw):
            self.fail(f"{what} reads past the end of its buffer view ({count} elements of {item} bytes, stride "
                      f"{stride}, from byte {offset} of {len(raw)}); re-export it")
        return _rows(raw, offset, count, item, stride)


def _rows(raw: memoryview, offset: int, count: int, item: int, stride: int) -> np.ndarray:
    """A contiguous copy of ``count`` elements of ``item`` bytes, ``stride`` apart from ``offset`` in ``raw``. The
    bounds were checked by the caller and are checked again here, right before ``as_strided``: it trusts them."""
    if not count:
        return np.zeros((0, item), np.uint8)
    extent = stride * (count - 1) + item
    if not (offset >= 0 and 0 < item <= stride and offset + extent <= len(raw)):
        raise ValueError(f"accessor bounds not checked: offset {offset}, {count} x {item} bytes, stride {stride}, "
                         f"{len(raw)} bytes")
    base = np.frombuffer(raw, np.uint8, count=extent, offset=offset)
    rows = np.lib.stride_tricks.as_strided(base, (count, item), (stride, 1), writeable=False)
    return np.ascontiguousarray(rows)
