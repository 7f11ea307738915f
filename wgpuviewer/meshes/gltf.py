"""glTF 2.0 meshes (``.gltf``, ``.glb``): the nodes' meshes placed by their transforms, with TANGENT, untextured
uvs and the first material's images (albedo, normal map) kept. A material's KHR_texture_transform (offset,
rotation, scale) is applied to the uvs (an affine map of the uvs is exact per vertex); the tangents are then
generated from the transformed uvs. A node whose transform is singular (a scale of 0: valid glTF, used to hide a
node) flattens its mesh: its primitives are left out with a warning naming it.

The file is parsed by pygltflib (``gltf_document`` says why pygltflib rather than gltflib: well kept, typed
dataclasses of the spec, GLB support). Its numbers are not trusted: every count, offset, stride and index is checked
(``gltf_accessors``) before our code decodes an accessor. Images a glTF embeds (data URIs, buffer views) are handed
to ``core.images`` as bytes (``ImageBytes``), never written to a temporary file.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from wgpuviewer.core.errors import FileError
from wgpuviewer.core.images import ImageBytes, read_header
from wgpuviewer.textures import TextureRef

from .gltf_accessors import Accessors
from .gltf_document import Document, read_document
from .model import FileMaterial, NodeNotFound, check_count
from .tangents import corner_vertices, transformed, triangle_areas

log = logging.getLogger("wgpuviewer.meshes")

_MODE_NAMES = {0: "points", 1: "lines", 2: "line loop", 3: "line strip", 5: "triangle strip", 6: "triangle fan"}
_IMAGE_TYPES = ("image/png", "image/jpeg")
#: Largest float32 coordinate.
FLOAT32_MAX = float(np.finfo(np.float32).max)


def read_gltf(path: Path, wanted: str | None, with_material: bool = True):
    """(vertex parts, material, node names, whether every part's tangents came from the file) of glTF file
    ``path``: all of it, or the node named ``wanted`` with its children; its material read (textures checked,
    texture transform applied) only ``with_material``."""
    doc = read_document(path)
    names = tuple(str(n.name or f"node{i}") for i, n in enumerate(doc.items("nodes")))
    placed = _placed_meshes(doc, names, wanted)
    data = Accessors(doc)
    primitives = _primitives(doc, data, placed)
    materials = [prim.material for prim, *_ in primitives]
    used = [m for m in dict.fromkeys(materials) if m is not None]
    if len(used) > 1:
        log.warning(f"{path}: {len(used)} materials on the mesh{f' of node {wanted!r}' if wanted else ''}; the first "
                    f"one's textures are used for all of it (give each material its own node and object)")
    material, uv_map = _material(doc, data, used[0]) if used and with_material else (None, None)
    parts, tangents_used, left_out = [], [], []
    for prim, world, where in primitives:
        if not np.isfinite(world).all():
            raise FileError(path, f"{where}: its node transforms multiply to infinity; re-export it with sensible "
                                  "scales")
        if _singular(world[:3, :3]):
            left_out.append(f"{where}: its node transform is flat (a scale of 0 or a singular matrix)")
            continue
        local, file_tangents = _primitive_vertices(data, prim, where, uv_map)
        placed = transformed(local, world[:3, :3], world[:3, 3])
        reach = float(np.max(np.abs(placed[:, :3]), initial=0.0))
        if reach > FLOAT32_MAX or ((triangle_areas(local) > 0).any()
                                   and not (triangle_areas(placed.astype(np.float32)) > 0).any()):
            left_out.append(f"{where}: its node transform places it {reach:.3g} from the origin, " + (
                "beyond float32's range" if reach > FLOAT32_MAX else "too far for float32 to keep its triangles' "
                                                                     "corners apart"))
            continue
        tangents_used.append(file_tangents)
        parts.append(placed)
    if left_out:
        _report_left_out(path, left_out, bool(parts))
    return parts, material, names, bool(tangents_used) and all(tangents_used)


def _report_left_out(path: Path, left_out: list[str], kept: bool) -> None:
    """A warning naming the primitives left out for their node transforms, or a FileError when nothing is left."""
    more = f" (and {len(left_out) - 1} more)" if len(left_out) > 1 else ""
    if not kept:
        raise FileError(path, f"{left_out[0]}{more}; nothing left to show: fix the node transforms")
    log.warning(f"{path}: left out {left_out[0]}{more}")


def _singular(linear: np.ndarray) -> bool:
    """Whether the 3x3 ``linear`` map flattens space (its determinant relative to its columns' lengths below
    1e-9: a scale of 0 on some axis, or columns in one plane)."""
    lengths = np.prod(np.linalg.norm(linear, axis=0))
    return not lengths > 0 or abs(np.linalg.det(linear)) <= 1e-9 * lengths


def _node_matrix(node) -> np.ndarray:
    if node.matrix is not None:
        return np.asarray(node.matrix, np.float64).reshape(4, 4).T  # column-major in the file
    x, y, z, w = node.rotation if node.rotation is not None else (0.0, 0.0, 0.0, 1.0)
    rotation = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    m = np.eye(4)
    m[:3, :3] = rotation * np.asarray(node.scale if node.scale is not None else (1.0, 1.0, 1.0), np.float64)
    m[:3, 3] = node.translation if node.translation is not None else (0.0, 0.0, 0.0)
    return m


def _placed_meshes(doc: Document, names: tuple[str, ...], wanted: str | None) -> list:
    """(mesh index, world matrix, node name) of every node with a mesh below the scene's roots, or below the node
    named ``wanted`` (placed as the file places it). A node reached twice (a cycle) is refused."""
    path, nodes = doc.path, doc.items("nodes")
    children = {c for n in nodes for c in n.children or []}
    if doc.items("scenes"):
        scene = doc.gltf.scene if doc.gltf.scene is not None else 0
        roots = doc.item("scenes", scene).nodes or []
    else:
        roots = [i for i in range(len(nodes)) if i not in children]
    if wanted is not None:
        matches = [i for i, name in enumerate(names) if name == wanted]
        if not matches:
            raise NodeNotFound(path, f"no node named {wanted!r} in {path.name}; its nodes: {', '.join(names) or 'none'}")
        if len(matches) > 1:
            raise FileError(path, f"{len(matches)} nodes are named {wanted!r}; expected one (rename them)")
    placed, stack, seen = [], [(r, np.eye(4), wanted is None) for r in roots], set()
    while stack:
        index, parent, inside = stack.pop()
        node = doc.item("nodes", index)
        if index in seen:
            raise FileError(path, f"nodes[{index}] is reached twice (a cycle or a shared child); re-export it")
        seen.add(index)
        world = parent @ _node_matrix(node)
        inside = inside or names[index] == wanted
        if inside and node.mesh is not None:
            placed.append((node.mesh, world, names[index]))
        stack.extend((c, world, inside) for c in node.children or [])
    if wanted is not None and not placed:
        raise NodeNotFound(path, f"node {wanted!r} has no mesh, nor have its children; its nodes: {', '.join(names)}")
    return placed


def _primitives(doc: Document, data: Accessors, placed: list) -> list:
    """(primitive, world matrix, where) of the placed meshes' primitives, each a triangle list with positions and
    uvs; their vertex count (after de-indexing) checked against the limit before any is read."""
    path, total, primitives = doc.path, 0, []
    for mesh_index, world, name in placed:
        for p, prim in enumerate(doc.item("meshes", mesh_index).primitives):
            where = f"node {name!r} mesh {mesh_index} primitive {p}"
            mode = 4 if prim.mode is None else prim.mode
            if mode != 4:
                raise FileError(path, f"{where}: {_MODE_NAMES.get(mode, f'mode {mode}')} are not supported; "
                                      "expected triangles (export triangulated)")
            attributes = prim.attributes
            if getattr(attributes, "POSITION", None) is None:
                raise FileError(path, f"{where}: no POSITION attribute; re-export it")
            if getattr(attributes, "TEXCOORD_0", None) is None:
                raise FileError(path, f"{where}: no TEXCOORD_0 (uv) attribute; relief mapping needs uvs: unwrap the "
                                      "mesh and export it with uvs")
            total += data.count(prim.indices if prim.indices is not None else attributes.POSITION, limit=False)
            check_count(path, total)
            primitives.append((prim, world, where))
    return primitives


def _primitive_vertices(data: Accessors, prim, where: str, uv_map: np.ndarray | None) -> tuple[np.ndarray, bool]:
    """(corners (n, 12) in the mesh's own space, whether the tangents came from the file) of a primitive; its uvs
    under ``uv_map`` (2x3, the material's texture transform) if given, the tangents then generated."""
    attributes = prim.attributes
    positions = data.accessor(attributes.POSITION)
    faces = data.accessor(prim.indices, indices=True) if prim.indices is not None else np.arange(len(positions))
    if len(faces) % 3:
        raise FileError(data.path, f"{where}: {len(faces)} indices, not a multiple of 3; re-export it")
    normals = data.accessor(attributes.NORMAL) if getattr(attributes, "NORMAL", None) is not None else None
    tangents = None
    if getattr(attributes, "TANGENT", None) is not None and normals is not None and uv_map is None:
        tangents = data.accessor(attributes.TANGENT)
        if tangents.shape[1] != 4:
            raise FileError(data.path, f"{where}: TANGENT has {tangents.shape[1]} components; expected VEC4")
        tangents[:, 3] *= -1  # glTF's bitangent points to image row 0 (its normal maps' +Y); ours to +v
    uv = data.accessor(attributes.TEXCOORD_0)
    for name, array in (("POSITION", positions), ("TEXCOORD_0", uv), ("NORMAL", normals), ("TANGENT", tangents)):
        if array is not None and array.shape[1] < (2 if name == "TEXCOORD_0" else 3):
            raise FileError(data.path, f"{where}: {name} has {array.shape[1]} components; re-export it")
        if array is not None and len(array) != len(positions):
            raise FileError(data.path, f"{where}: {name} has {len(array)} elements for {len(positions)} positions; "
                                       "expected one per vertex (re-export it)")
    uv = uv[:, :2] if uv_map is None else uv[:, :2] @ uv_map[:, :2].T + uv_map[:, 2]
    local = corner_vertices(data.path, where, positions[:, :3], uv, faces,
                            None if normals is None else normals[:, :3], tangents)
    return local, tangents is not None


def _material(doc: Document, data: Accessors, index: int) -> tuple[FileMaterial, np.ndarray | None]:
    """Material ``index`` and the texture transform (2x3, None: none) its textures share."""
    spec = doc.item("materials", index)
    where = f"materials[{index}]"
    name = str(spec.name or where)
    pbr = spec.pbrMetallicRoughness
    factor = pbr.baseColorFactor if pbr is not None and pbr.baseColorFactor is not None else [1.0, 1.0, 1.0, 1.0]
    albedo = _image_ref(doc, data, pbr.baseColorTexture if pbr else None, "baseColorTexture", where)
    if albedo is not None and any(abs(c - 1.0) > 1e-6 for c in factor[:3]):
        log.warning(f"{doc.path}: {where} baseColorFactor {factor[:3]} is not applied to its baseColorTexture")
    normal = _image_ref(doc, data, spec.normalTexture, "normalTexture", where)
    color = tuple(float(np.clip(c, 0.0, 1.0)) for c in factor[:3])
    return FileMaterial(name, albedo=albedo, color=color, normal=normal), _shared_transform(doc.path, spec, where)


def _uv_map(transform: dict) -> np.ndarray:
    """The 2x3 affine map of a KHR_texture_transform: uv' = T(offset) R(rotation) S(scale) uv, R turning the uvs
    counter-clockwise as the ratified extension defines it (u' = c u + s v, v' = -s u + c v)."""
    sx, sy = transform.get("scale", (1.0, 1.0))
    c, s = np.cos(transform.get("rotation", 0.0)), np.sin(transform.get("rotation", 0.0))
    ox, oy = transform.get("offset", (0.0, 0.0))
    return np.array([[c * sx, s * sy, ox], [-s * sx, c * sy, oy]])


def _shared_transform(path: Path, spec, where: str) -> np.ndarray | None:
    """The texture transform of material ``spec``'s textures (None: none), which must be one for all of them: it is
    applied to the mesh's uvs, which every texture shares."""
    pbr = spec.pbrMetallicRoughness
    infos = {"baseColorTexture": pbr.baseColorTexture if pbr else None, "normalTexture": spec.normalTexture}
    maps = {slot: _uv_map((info.extensions or {}).get("KHR_texture_transform", {}))
            for slot, info in infos.items() if info is not None and info.index is not None}
    if not maps:
        return None
    first, *others = maps.items()
    for slot, other in others:
        if not np.allclose(first[1], other, atol=1e-9):
            raise FileError(path, f"{where}: {first[0]} and {slot} have different KHR_texture_transforms; expected one "
                                  "for all of the material's textures (bake them into the images or the uvs)")
    return None if np.allclose(first[1], _uv_map({}), atol=0) else first[1]


def _image_ref(doc: Document, data: Accessors, info, slot: str, where: str) -> TextureRef | None:
    """The TextureRef of a material's texture (``{"index": i}``): an external image file, or the bytes of an
    embedded one (a buffer view or data URI), its header checked."""
    if info is None or info.index is None:
        return None
    path = doc.path
    if info.texCoord:
        log.warning(f"{path}: {where} {slot} uses TEXCOORD_{info.texCoord}; read with TEXCOORD_0")
    transform_coord = (info.extensions or {}).get("KHR_texture_transform", {}).get("texCoord", 0)
    if transform_coord:
        log.warning(f"{path}: {where} {slot}'s KHR_texture_transform names TEXCOORD_{transform_coord}; read with "
                    "TEXCOORD_0")
    texture = doc.item("textures", info.index)
    if texture.source is None:
        raise FileError(path, f"{where}: textures[{info.index}] has no image source (an extension's image format?); "
                              "expected a PNG or JPEG image")
    image = doc.item("images", texture.source)
    what = f"images[{texture.source}] ({slot} of {where})"
    uri = image.uri
    if uri is not None and not uri.startswith("data:"):
        source = data.external_file(uri, what)
    else:
        if uri is not None:
            content, mime = data.data_uri(uri, what), uri[5:].partition(";")[0]
        elif image.bufferView is not None:
            content, mime = bytes(data.view(image.bufferView)[0]), image.mimeType or ""
        else:
            raise FileError(path, f"{what}: neither uri nor bufferView; re-export it")
        if mime not in _IMAGE_TYPES:
            raise FileError(path, f"{what}: image type {mime or 'unknown'}; expected image/png or image/jpeg")
        source = ImageBytes(f"{path}: images[{texture.source}]", content)
    try:
        read_header(source)
    except FileError as error:
        raise FileError(path, f"{what}: {error.reason}") from None
    return TextureRef("file", path=source, origin=f"{path}: {what}")
