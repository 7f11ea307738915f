"""Wavefront OBJ files: geometry through trimesh's parser (faces of any size, negative and split position/uv/normal
indices, ``o`` objects as the nodes a scene's ``node`` key picks), and the first ``usemtl`` material from its
``mtllib`` files (map_Kd, Kd, norm, map_Bump / bump), read here line by line.

Before trimesh sees the file: its text is decoded here (``obj_text``: UTF-8, or Latin-1 for the legacy names and
comments of old exporters; UTF-16/32 and binary files are refused by name, where trimesh would guess with a module we
do not install), and its face lines are counted against ``MAX_MESH_VERTICES`` (each face is at least one triangle):
trimesh's parser holds about 30 times the file's size, so a file far beyond the limit is refused before it parses."""

from __future__ import annotations

import io
import logging
import math
import re
from pathlib import Path

import numpy as np

from wgpuviewer.core.errors import FileError
from wgpuviewer.core.images import read_header, resolve_path
from wgpuviewer.textures import TextureRef

from .model import FileMaterial, NodeNotFound, check_count
from .tangents import corner_vertices

log = logging.getLogger("wgpuviewer.meshes")


#: Byte-order marks of the encodings an OBJ file may not have (it is ASCII/UTF-8 text): UTF-32 before UTF-16.
_BOMS = {b"\xff\xfe\x00\x00": "UTF-32", b"\x00\x00\xfe\xff": "UTF-32", b"\xff\xfe": "UTF-16",
         b"\xfe\xff": "UTF-16"}


def obj_text(path: Path, data: bytes) -> str:
    """The text of OBJ (or MTL) file ``path`` of bytes ``data``: UTF-8 (a BOM dropped), else Latin-1 (every byte
    is a character: old exporters write names in legacy code pages). UTF-16/32 and binary files are FileErrors
    naming the encoding and the fix."""
    for bom, encoding in _BOMS.items():
        if data.startswith(bom):
            raise FileError(path, f"text encoded as {encoding}; OBJ and MTL files are ASCII or UTF-8 text: save it as "
                                  "UTF-8")
    if b"\x00" in data:
        return _refuse_binary(path, data)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _refuse_binary(path: Path, data: bytes):
    at = data.index(b"\x00")
    utf16 = data[1::2].count(0) > len(data) // 4 or data[0::2].count(0) > len(data) // 4
    what = "UTF-16 text without a byte-order mark" if utf16 else f"a binary file (a NUL byte at byte {at})"
    raise FileError(path, f"{what}; OBJ and MTL files are ASCII or UTF-8 text: save it as UTF-8")


def face_lines(text: str) -> int:
    """How many lines of ``text`` start with an ``f`` statement (``f`` then a space or tab; indented ones are not
    counted): a lower bound of its triangles, counted at the speed of ``str.count`` (8 million faces in under a second)."""
    return text.count("\nf ") + text.count("\nf\t") + text.startswith(("f ", "f\t"))


def read_obj(path: Path, wanted: str | None, with_material: bool = True):
    text = obj_text(path, path.read_bytes())
    check_count(path, 3 * face_lines(text))
    from trimesh.exchange.obj import load_obj  # trimesh takes 0.6 s to import: only a scene with an OBJ pays it
    from trimesh.geometry import triangulate_quads
    try:
        loaded = load_obj(io.StringIO(text), skip_materials=True, split_objects=True, group_material=False)
        # its parser gives the objects last first, and quads as quads
        geometry = dict(reversed(loaded.get("geometry", {}).items())) if isinstance(loaded, dict) else {}
        for part in geometry.values():
            part["faces"] = triangulate_quads(part.get("faces", np.zeros((0, 3), np.int64)))
    except Exception as error:  # trimesh raises whatever its parser meets
        raise FileError(path, f"cannot read as OBJ ({type(error).__name__}: {error}); re-export it") from None
    names = tuple(geometry)
    if wanted is not None and wanted not in geometry:
        raise NodeNotFound(path, f"no object named {wanted!r} in {path.name}; its objects: {', '.join(names) or 'none'}")
    parts = []
    total = 0
    for name, part in geometry.items():
        if wanted is not None and name != wanted:
            continue
        faces = np.asarray(part["faces"], np.int64)
        total += 3 * len(faces)
        check_count(path, total)
        visual = part.get("visual")
        uv = getattr(visual, "uv", None)
        if uv is None or len(uv) != len(part["vertices"]):
            raise FileError(path, f"object {name!r} has no uvs (vt); relief mapping needs uvs: unwrap the mesh and "
                                  "export it with uvs")
        uv = np.asarray(uv, np.float64).copy()
        uv[:, 1] = 1.0 - uv[:, 1]  # OBJ's vt has v up from the image's bottom row; ours starts at its top row
        parts.append(corner_vertices(path, f"object {name!r}", part["vertices"], uv, faces,
                                     part.get("vertex_normals")))
    return parts, _obj_material(path, text) if with_material else None, names, False


def _mtl_path(token_line: str) -> str:
    """The file name of an .mtl map statement's arguments (options such as ``-bm 1.0`` come first)."""
    return token_line.split()[-1]


def _obj_material(path: Path, text: str) -> FileMaterial | None:
    """The material of the OBJ's first ``usemtl``, from its ``mtllib``: map_Kd (albedo), Kd (colour), norm
    (normal map), map_Bump / bump (height map, as the MTL format defines it)."""
    used = list(dict.fromkeys(re.findall(r"^\s*usemtl\s+(.+?)\s*$", text, re.MULTILINE)))
    libraries = re.findall(r"^\s*mtllib\s+(.+?)\s*$", text, re.MULTILINE)
    if not used:
        return None
    if len(used) > 1:
        log.warning(f"{path}: {len(used)} materials (usemtl); the first one's ({used[0]}) textures are used for all "
                    "of it (put each material in its own object and name it with node = ...)")
    for library in libraries:
        try:
            mtl = resolve_path(path.parent / library)
        except FileError as error:
            raise FileError(path, f"mtllib {library!r}: {error.reason}") from None
        if not mtl.is_file():
            raise FileError(path, f"mtllib {library!r} not found (looked for {mtl})")
        statements: dict[str, dict[str, str]] = {}
        current = None
        try:
            lines = obj_text(mtl, mtl.read_bytes()).splitlines()
        except FileError as error:
            raise FileError(path, f"mtllib {library!r}: {error.reason}") from None
        for line in lines:
            key, _, rest = line.strip().partition(" ")
            if key == "newmtl":
                current = statements.setdefault(rest.strip(), {})
            elif current is not None and rest.strip():
                current[key.lower()] = rest.strip()
        if used[0] in statements:
            return _mtl_material(path, mtl, used[0], statements[used[0]])
    raise FileError(path, f"material {used[0]!r} (usemtl) is in none of its mtllib files "
                          f"({', '.join(libraries) or 'none named'})")


def _mtl_material(path: Path, mtl: Path, name: str, found: dict[str, str]) -> FileMaterial:
    """The FileMaterial of .mtl material ``name`` (its statements ``found``: key -> arguments)."""

    def ref(*keys):
        key = next((k for k in keys if k in found), None)
        if key is None:
            return None
        file_name = _mtl_path(found[key])
        what = f"{mtl.name}: material {name!r} {key} {file_name!r}"
        try:
            file = resolve_path(mtl.parent / file_name)
        except FileError as error:
            raise FileError(path, f"{what}: {error.reason}") from None
        if not file.is_file():
            raise FileError(path, f"{what}: file not found (looked for {file})")
        try:
            read_header(file)
        except FileError as error:
            raise FileError(path, f"{what}: {error.reason}") from None
        return TextureRef("file", path=file, origin=f"{path}: {what}")

    color = None
    if "kd" in found:
        try:
            color = tuple(float(x) for x in found["kd"].split())
        except ValueError:
            color = ()
        if len(color) != 3 or not all(math.isfinite(c) for c in color):
            raise FileError(path, f"{mtl.name}: material {name!r} Kd {found['kd']!r}: expected 3 finite numbers")
        color = tuple(float(np.clip(c, 0.0, 1.0)) for c in color)
    return FileMaterial(name, albedo=ref("map_kd"), color=color, normal=ref("norm"), height=ref("map_bump", "bump"))
