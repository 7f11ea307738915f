"""A glTF 2.0 file's document: pygltflib parses it (the JSON, the GLB chunks, the document model); what comes before
and after is ours. pygltflib rather than gltflib: it is well kept (regular releases for current Pythons), its model
is typed dataclasses of the spec, and it reads GLB as well as .gltf with its buffers.

Before: a GLB's framing is checked (magic, version, declared length against the file's, every chunk inside the
file, the JSON chunk first), and the JSON's values are checked against the types of every key we read (``SCHEMA``):
pygltflib's decoder coerces what it meets (a ``uri`` of 5 becomes ``"5"``, an ``asset`` of ``"2.0"`` fails deep
inside it), so a value of the wrong type is named here by its key (``buffers[0].uri = 5: expected a string``).
After: ``extensionsRequired`` naming an extension we do not implement is refused by name (Draco and meshopt: their
accessors hold no plain data), and the version must be 2.x. KHR_texture_transform is implemented (``gltf`` applies
it to the uvs), required or not.
"""

from __future__ import annotations

import json
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

from pygltflib import GLTF2

from wgpuviewer.core.errors import FileError

_GLB_MAGIC = b"glTF"
_JSON_CHUNK, _BIN_CHUNK = 0x4E4F534A, 0x004E4942

#: Extensions a file may require: KHR_mesh_quantization only widens the component types of attributes, which the
#: accessor reader takes as they come; KHR_texture_transform is applied to the uvs (``gltf``).
SUPPORTED_EXTENSIONS = frozenset({"KHR_mesh_quantization", "KHR_texture_transform"})
#: The fix for a required extension we do not implement.
_EXTENSION_FIXES = {
    "KHR_draco_mesh_compression": "export without Draco compression",
    "EXT_meshopt_compression": "export without meshopt compression",
}

INT, NUMBER, STRING, BOOL, OBJECT = "an integer", "a number", "a string", "true or false", "an object"
_TEXTURE_INFO = {"index!": INT, "texCoord": INT, "extensions": {
    "KHR_texture_transform": {"offset": [NUMBER, 2], "rotation": NUMBER, "scale": [NUMBER, 2], "texCoord": INT}}}
#: The types of every key read (``name!``: required). ``{...}``: an object; ``[T]``: an array of T; ``[T, n]``: n
#: of them; ``{"*": T}``: an object whose every value is a T.
SCHEMA = {
    "asset!": {"version!": STRING},
    "extensionsRequired": [STRING],
    "extensionsUsed": [STRING],
    "scene": INT,
    "scenes": [{"nodes": [INT]}],
    "nodes": [{"name": STRING, "mesh": INT, "children": [INT], "matrix": [NUMBER, 16], "translation": [NUMBER, 3],
               "rotation": [NUMBER, 4], "scale": [NUMBER, 3]}],
    "meshes": [{"primitives!": [{"attributes!": {"*": INT}, "indices": INT, "mode": INT, "material": INT}]}],
    "accessors": [{"bufferView": INT, "byteOffset": INT, "componentType!": INT, "normalized": BOOL, "count!": INT,
                   "type!": STRING, "sparse": OBJECT}],
    "bufferViews": [{"buffer!": INT, "byteOffset": INT, "byteLength!": INT, "byteStride": INT}],
    "buffers": [{"uri": STRING, "byteLength!": INT}],
    "images": [{"uri": STRING, "mimeType": STRING, "bufferView": INT}],
    "textures": [{"source": INT}],
    "materials": [{"name": STRING, "normalTexture": _TEXTURE_INFO,
                   "pbrMetallicRoughness": {"baseColorFactor": [NUMBER, 4], "baseColorTexture": _TEXTURE_INFO}}],
}


@dataclass
class Document:
    """A checked glTF document: pygltflib's ``gltf``, the GLB's binary chunk (None for .gltf), and the file."""

    path: Path
    gltf: GLTF2
    binary: bytes | None

    def items(self, key: str) -> list:
        return getattr(self.gltf, key) or []

    def item(self, key: str, index):
        """``key[index]`` of the document, or a FileError naming the reference."""
        items = self.items(key)
        if not (isinstance(index, int) and not isinstance(index, bool) and 0 <= index < len(items)):
            raise FileError(self.path, f"refers to {key}[{index}], which it does not have; re-export it")
        return items[index]


def read_document(path: Path) -> Document:
    """The checked document of glTF file ``path`` (.gltf or .glb); every problem a one-line FileError."""
    data = path.read_bytes()
    if path.suffix.lower() == ".glb":
        length, json_bytes = _glb_json(path, data)
    else:
        length, json_bytes = len(data), data
    try:
        doc = json.loads(json_bytes)
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as error:
        raise FileError(path, f"not a glTF file (its JSON does not parse: {error}); re-export it") from None
    if not isinstance(doc, dict):
        raise FileError(path, "not a glTF file (its JSON is no object); re-export it")
    _check_types(path, doc, SCHEMA, "")
    version = doc["asset"]["version"]
    if not version.startswith("2."):
        raise FileError(path, f"glTF version {version or 'missing'}; expected 2.0")
    for name in doc.get("extensionsRequired", []):
        if name not in SUPPORTED_EXTENSIONS:
            fix = _EXTENSION_FIXES.get(name, "export without it")
            raise FileError(path, f"extensionsRequired names {name}, which is not supported; {fix}")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # pygltflib warns of chunk types it skips, as the spec asks
            gltf = GLTF2.load_from_bytes(data[:length]) if path.suffix.lower() == ".glb" else \
                GLTF2.gltf_from_json(json_bytes.decode("utf-8-sig"))
    except Exception as error:  # noqa: BLE001 - pygltflib's decoder raises whatever it meets in keys we do not read
        raise FileError(path, f"malformed glTF ({type(error).__name__}: {error}); re-export it") from None
    binary = gltf.binary_blob() if path.suffix.lower() == ".glb" else None
    return Document(path, gltf, binary)


def _glb_json(path: Path, data: bytes) -> tuple[int, bytes]:
    """(declared length, JSON chunk) of a GLB, its framing checked: the magic, version 2, the declared length
    within the file, every chunk within the declared length, the JSON chunk first (as the spec and pygltflib
    want it)."""
    if len(data) < 20 or data[:4] != _GLB_MAGIC:
        raise FileError(path, "not a GLB file (no 'glTF' magic at its start); expected binary glTF 2.0")
    version, length = (int.from_bytes(data[at:at + 4], "little") for at in (4, 8))
    if version != 2:
        raise FileError(path, f"GLB version {version}; expected 2")
    if length > len(data):
        raise FileError(path, f"truncated: its header says {length} bytes, the file has {len(data)}")
    chunks, at = [], 12
    while at < length:
        if at + 8 > length:
            raise FileError(path, f"truncated: a chunk header runs past the end of the file at byte {at}")
        size, kind = (int.from_bytes(data[i:i + 4], "little") for i in (at, at + 4))
        if at + 8 + size > length:
            raise FileError(path, f"truncated: a chunk runs past the end of the file at byte {at}")
        chunks.append((kind, at + 8, size))
        at += 8 + size
    if not chunks or chunks[0][0] != _JSON_CHUNK:
        what = "without a JSON chunk" if all(k != _JSON_CHUNK for k, *_ in chunks) else "whose first chunk is not JSON"
        raise FileError(path, f"GLB {what}; re-export it")
    _, start, size = chunks[0]
    return length, data[start:start + size]


def _show(value) -> str:
    text = json.dumps(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _check_types(path: Path, value, spec, key: str) -> None:
    """``value`` (at ``key``) is of ``spec``'s type (``SCHEMA``), or a FileError names the key."""
    if isinstance(spec, dict):
        if not isinstance(value, dict):
            _refuse(path, key, value, OBJECT)
        for name, sub in spec.items():
            if name == "*":
                for k, v in value.items():
                    _check_types(path, v, sub, f"{key}.{k}")
                continue
            required, name = name.endswith("!"), name.rstrip("!")
            if name in value:
                _check_types(path, value[name], sub, f"{key}.{name}" if key else name)
            elif required:
                raise FileError(path, f"{key + '.' if key else ''}{name}: missing (it is required); re-export it")
    elif isinstance(spec, list):
        length = spec[1] if len(spec) > 1 else None
        if not isinstance(value, list) or (length is not None and len(value) != length):
            _refuse(path, key, value, f"an array of {length} numbers" if length else "an array")
        for i, item in enumerate(value):
            _check_types(path, item, spec[0], f"{key}[{i}]")
    elif not _is(value, spec):
        _refuse(path, key, value, spec)


def _is(value, kind: str) -> bool:
    if kind == STRING:
        return isinstance(value, str)
    if kind == BOOL:
        return isinstance(value, bool)
    if kind == OBJECT:
        return isinstance(value, dict)
    if isinstance(value, bool) or not isinstance(value, int | float):
        return False
    return isinstance(value, int) if kind == INT else math.isfinite(value)


def _refuse(path: Path, key: str, value, expected: str):
    raise FileError(path, f"{key} = {_show(value)}: expected {expected}; re-export it")
