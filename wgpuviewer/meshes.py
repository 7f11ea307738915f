"""Meshes with tangent frames: the builtin shapes (plane, quad, box, sphere, cylinder, torus) and meshes read from
glTF 2.0 (``.gltf``, ``.glb``) and Wavefront OBJ files.

Vertex layout (48 bytes): position xyz, normal xyz, tangent xyzw (w = bitangent handedness), uv.
u runs along the tangent, v along the bitangent ``w * cross(normal, tangent)``; image row 0 is v = 0.
Every mesh is a non-indexed triangle list, front faces counter-clockwise seen from outside.

Files: glTF is read here (its JSON, buffers and accessors: a few numpy lines, and what trimesh's glTF loader drops,
TANGENT, untextured UVs and the images' own bytes, is kept); OBJ through trimesh (faces of any size, negative and
split position/uv/normal indices), its ``.mtl`` here. A file's mesh is read once per file, node and modification
time (``load_mesh``). Images a glTF embeds are written once to a private temporary folder, so ``core.images`` reads
them like any texture file.
"""

from __future__ import annotations

import atexit
import base64
import hashlib
import io
import json
import logging
import math
import re
import shutil
import tempfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from urllib.parse import unquote

import numpy as np

from wgpuviewer.core.errors import FileError
from wgpuviewer.core.images import read_header

from .textures import TextureRef

log = logging.getLogger("wgpuviewer.meshes")

VERTEX_STRIDE = 48
VERTEX_ATTRIBUTES = [
    {"format": "float32x3", "offset": 0, "shader_location": 0},
    {"format": "float32x3", "offset": 12, "shader_location": 1},
    {"format": "float32x4", "offset": 24, "shader_location": 2},
    {"format": "float32x2", "offset": 40, "shader_location": 3},
]
#: Floats per vertex: position 3, normal 3, tangent 4, uv 2.
VERTEX_FLOATS = VERTEX_STRIDE // 4


def _face(origin, u_axis, v_axis) -> np.ndarray:
    """Two triangles spanning origin + u*u_axis + v*v_axis, u, v in [0, 1], front face counter-clockwise."""
    origin, u_axis, v_axis = (np.asarray(a, np.float64) for a in (origin, u_axis, v_axis))
    normal = np.cross(v_axis, u_axis)
    normal /= np.linalg.norm(normal)
    tangent = u_axis / np.linalg.norm(u_axis)
    handedness = np.sign(np.dot(np.cross(normal, tangent), v_axis))
    corners = [(0, 0), (0, 1), (1, 1), (1, 0)]
    verts = [
        np.concatenate([origin + u * u_axis + v * v_axis, normal, tangent, [handedness], [u, v]]) for u, v in corners
    ]
    return np.array([verts[i] for i in (0, 1, 2, 0, 2, 3)], np.float32)


def plane(width: float, depth: float) -> np.ndarray:
    """Horizontal plane at y = 0 facing +Y, centred; u along +X, v along +Z."""
    return _face((-width / 2, 0, -depth / 2), (width, 0, 0), (0, 0, depth))


def quad(width: float, height: float) -> np.ndarray:
    """Vertical quad at z = 0 facing +Z, centred; u along +X, v along -Y (image rows go down)."""
    return _face((-width / 2, height / 2, 0), (width, 0, 0), (0, -height, 0))


def box(sx: float, sy: float, sz: float) -> np.ndarray:
    hx, hy, hz = sx / 2, sy / 2, sz / 2
    faces = [
        _face((-hx, hy, hz), (sx, 0, 0), (0, -sy, 0)),  # +Z
        _face((hx, hy, -hz), (-sx, 0, 0), (0, -sy, 0)),  # -Z
        _face((hx, hy, hz), (0, 0, -sz), (0, -sy, 0)),  # +X
        _face((-hx, hy, -hz), (0, 0, sz), (0, -sy, 0)),  # -X
        _face((-hx, hy, -hz), (sx, 0, 0), (0, 0, sz)),  # +Y
        _face((-hx, -hy, hz), (sx, 0, 0), (0, 0, -sz)),  # -Y
    ]
    return np.concatenate(faces)


# ----------------------------------------------------------------------------------------------
# Curved builtins: parametric surfaces with analytic normals and tangents. u runs around (longitude), v along
# (from the top down), so seen from outside u goes right and v down, as on a quad. The seam u = 1 (and v = 1 of
# the torus) has its own vertices, copies of u = 0 with the other uv.

#: Tessellation: quads around (u) x along (v).
SPHERE_GRID = (48, 24)
CYLINDER_SEGMENTS = 48
TORUS_GRID = (48, 24)


def _frame_vertices(position, normal, tangent, along_v, uv) -> np.ndarray:
    """(n, 12) vertices from float64 arrays (n, 3) and uv (n, 2); handedness w from the direction of +v."""
    w = np.sign(np.einsum("ij,ij->i", np.cross(normal, tangent), along_v))
    return np.concatenate([position, normal, tangent, w[:, None], uv], axis=1)


def _grid(surface, nu: int, nv: int, drop_degenerate: bool = False, closed_v: bool = False) -> np.ndarray:
    """Triangles of the parametric ``surface(u, v) -> (position, normal, tangent, d position / d v)`` over an
    (nu + 1) x (nv + 1) vertex grid. Quad (i, j) is (a, b, c), (a, c, d) with a = (u_i, v_j), b = (u_i, v_j+1),
    c = (u_i+1, v_j+1), d = (u_i+1, v_j): counter-clockwise where the outward normal is d/dv x d/du.
    ``drop_degenerate``: leave out triangles with two corners at one point (a sphere's poles). The surface closes
    at u = 1 (and at v = 1 where ``closed_v``): the seam's copies are evaluated at 0, so both sides of it share
    bit-identical positions and the rasteriser leaves no crack between them."""
    u, v = np.meshgrid(np.arange(nu + 1) / nu, np.arange(nv + 1) / nv, indexing="ij")
    u, v = u.ravel(), v.ravel()
    verts = _frame_vertices(*surface(u % 1.0, v % 1.0 if closed_v else v), np.stack([u, v], axis=1))
    index = np.arange((nu + 1) * (nv + 1)).reshape(nu + 1, nv + 1)
    a, b, c, d = index[:-1, :-1], index[:-1, 1:], index[1:, 1:], index[1:, :-1]
    tris = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    if drop_degenerate:
        p = verts[:, :3][tris]
        area = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
        tris = tris[area > 1e-9 * np.max(area)]
    return verts[tris.ravel()].astype(np.float32)


def sphere(radius: float) -> np.ndarray:
    """Sphere at the origin: u = longitude from +Z towards +X, v = colatitude from the north pole (+Y, v = 0)."""

    def surface(u, v):
        phi, theta = 2 * np.pi * u, np.pi * v
        normal = np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), np.sin(theta) * np.cos(phi)], 1)
        tangent = np.stack([np.cos(phi), np.zeros_like(phi), -np.sin(phi)], 1)
        along_v = np.stack([np.cos(theta) * np.sin(phi), -np.sin(theta), np.cos(theta) * np.cos(phi)], 1)
        return radius * normal, normal, tangent, along_v

    return _grid(surface, *SPHERE_GRID, drop_degenerate=True)


def _cap(radius: float, y: float, up: bool) -> np.ndarray:
    """A disc at height y facing +Y (``up``) or -Y; planar uv as a plane's (u along +X, v along +Z on top,
    -Z below, so both read unmirrored from outside)."""
    n = CYLINDER_SEGMENTS
    phi = 2 * np.pi * np.arange(n + 1) / n
    rim = np.stack([radius * np.sin(phi), np.full_like(phi, y), radius * np.cos(phi)], 1)
    points = np.concatenate([[[0.0, y, 0.0]], rim])
    flip = 1.0 if up else -1.0
    uv = np.stack([0.5 + points[:, 0] / (2 * radius), 0.5 + flip * points[:, 2] / (2 * radius)], 1)
    ones = np.ones((n + 2, 1))
    verts = _frame_vertices(points, ones * [0.0, flip, 0.0], ones * [1.0, 0.0, 0.0], ones * [0.0, 0.0, flip], uv)
    k = np.arange(1, n + 1)
    tris = np.stack([np.zeros(n, int), k, k + 1] if up else [np.zeros(n, int), k + 1, k], 1)
    return verts[tris.ravel()]


def cylinder(radius: float, height: float) -> np.ndarray:
    """Closed cylinder along Y, centred: the side's u = angle from +Z towards +X, v from the top rim (v = 0) to
    the bottom; the caps are planar discs."""

    def surface(u, v):
        phi = 2 * np.pi * u
        normal = np.stack([np.sin(phi), np.zeros_like(phi), np.cos(phi)], 1)
        position = radius * normal + np.stack([0 * phi, height * (0.5 - v), 0 * phi], 1)
        tangent = np.stack([np.cos(phi), np.zeros_like(phi), -np.sin(phi)], 1)
        along_v = np.tile([0.0, -1.0, 0.0], (len(u), 1))
        return position, normal, tangent, along_v

    side = _grid(surface, CYLINDER_SEGMENTS, 1)
    return np.concatenate([side, _cap(radius, height / 2, True), _cap(radius, -height / 2, False)]).astype(np.float32)


def torus(major: float, minor: float) -> np.ndarray:
    """Torus around the Y axis: u = angle around Y from +Z towards +X, v = angle around the tube from its
    outer equator, first downwards (v = 0.25 is the underside, 0.75 the top)."""

    def surface(u, v):
        phi, psi = 2 * np.pi * u, 2 * np.pi * v
        radial = np.stack([np.sin(phi), np.zeros_like(phi), np.cos(phi)], 1)
        up = np.array([0.0, 1.0, 0.0])
        normal = np.cos(psi)[:, None] * radial - np.sin(psi)[:, None] * up
        position = major * radial + minor * normal
        tangent = np.stack([np.cos(phi), np.zeros_like(phi), -np.sin(phi)], 1)
        along_v = -np.sin(psi)[:, None] * radial - np.cos(psi)[:, None] * up
        return position, normal, tangent, along_v

    return _grid(surface, *TORUS_GRID, closed_v=True)


#: Builtin object kind -> (its size keys, documented in order, its vertex builder).
BUILTIN_SHAPES = {
    "plane": (("width", "depth"), plane),
    "quad": (("width", "height"), quad),
    "box": (("x", "y", "z"), box),
    "sphere": (("radius",), sphere),
    "cylinder": (("radius", "height"), cylinder),
    "torus": (("major radius", "minor radius"), torus),
}


def build(kind: str, size) -> np.ndarray:
    if kind not in BUILTIN_SHAPES:
        raise ValueError(f"unknown mesh kind {kind!r}")
    return BUILTIN_SHAPES[kind][1](*size)


def for_object(obj) -> np.ndarray:
    """The vertices of a scene object (``scene.SceneObject``), in this module's layout: a builtin shape of its
    ``size``, or a mesh file's (``load_mesh``) scaled by its ``scale``."""
    if obj.kind == "mesh":
        mesh = load_mesh(obj.file, obj.node)
        return transformed(mesh.vertices, np.diag(obj.scale)).astype(np.float32)
    return build(obj.kind, obj.size)


def transformed(vertices: np.ndarray, matrix: np.ndarray, offset=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(n, 12) vertices under the linear map ``matrix`` (3x3) then ``offset``, float64: normals by the inverse
    transpose, tangents by the matrix, the handedness kept to the transformed bitangent, and each triangle's
    corners reversed where the map mirrors (determinant < 0), so front faces stay counter-clockwise."""
    m = np.asarray(matrix, np.float64)
    v = np.asarray(vertices, np.float64)
    normal_matrix = np.linalg.inv(m).T
    n, t = v[:, 3:6], v[:, 6:9]
    bitangent = v[:, 9:10] * np.cross(n, t)
    n2 = _unit(n @ normal_matrix.T)
    t2 = t @ m.T
    t2 = _unit(t2 - n2 * np.einsum("ij,ij->i", t2, n2)[:, None])
    w = np.where(np.einsum("ij,ij->i", np.cross(n2, t2), bitangent @ m.T) < 0, -1.0, 1.0)
    out = np.concatenate([v[:, :3] @ m.T + offset, n2, t2, w[:, None], v[:, 10:12]], axis=1)
    if np.linalg.det(m) < 0:
        out = out.reshape(-1, 3, VERTEX_FLOATS)[:, ::-1].reshape(-1, VERTEX_FLOATS)
    return out


def _unit(v: np.ndarray) -> np.ndarray:
    length = np.linalg.norm(v, axis=1, keepdims=True)
    return v / np.where(length > 0, length, 1.0)


# ----------------------------------------------------------------------------------------------
# Mesh files.

MESH_SUFFIXES = (".glb", ".gltf", ".obj")
#: Most vertices one mesh object may have (3 per triangle after de-indexing): 2^21 vertices are 96 MiB of vertex
#: buffer, and the software adapter draws about that many in a few seconds. Counted from the file's accessor
#: counts (glTF) or faces (OBJ) before the vertex data is assembled.
MAX_MESH_VERTICES = 1 << 21
#: Largest mesh file read, checked before it is read: 1 GiB.
MAX_MESH_FILE_BYTES = 1 << 30


class NodeNotFound(FileError):
    """The ``node`` asked for is not in the mesh file (the reason lists the names it has)."""


@dataclass(frozen=True)
class FileMaterial:
    """The textures a mesh file gives its mesh (None where it gives none): albedo image, constant colour (glTF's
    baseColorFactor, OBJ's Kd; used where there is no albedo image), normal map, height map (OBJ's bump)."""

    name: str
    albedo: TextureRef | None = None
    color: tuple[float, float, float] | None = None
    normal: TextureRef | None = None
    height: TextureRef | None = None


@dataclass(frozen=True)
class MeshData:
    """A mesh file's vertices (n, 12) float32 (read-only) in the file's units with its node transforms applied;
    the material of its first triangles; the names the ``node`` key may take; how many zero-area triangles were
    dropped; whether the tangents came from the file (glTF TANGENT) or were generated."""

    vertices: np.ndarray
    material: FileMaterial | None
    names: tuple[str, ...]
    dropped: int
    file_tangents: bool

    def half_extents(self, scale) -> tuple[float, float, float]:
        """Half the sides of the smallest origin-centred box holding the mesh scaled by ``scale``."""
        reach = np.max(np.abs(self.vertices[:, :3].astype(np.float64)), axis=0) * np.asarray(scale)
        return tuple(float(x) for x in reach)


def load_mesh(path: Path, node: str | None = None) -> MeshData:
    """The mesh of file ``path`` (glTF 2.0 or OBJ), all of it or the node/object named ``node`` with its children.
    Read once per file, node, size and modification time. Raises FileError (reason: what is wrong, the fix)."""
    path = Path(path)
    try:
        stat = path.stat()
    except OSError as error:
        raise FileError(path, f"cannot read ({error.strerror or error})") from None
    return _load_mesh(path, node, stat.st_mtime_ns, stat.st_size)


@lru_cache(maxsize=16)
def _load_mesh(path: Path, node: str | None, mtime_ns: int, size: int) -> MeshData:
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise FileError(path, f"unsupported mesh file type {path.suffix!r}; expected {', '.join(MESH_SUFFIXES)}")
    if not path.is_file():
        raise FileError(path, "not a file; expected a mesh file")
    if size > MAX_MESH_FILE_BYTES:
        raise FileError(path, f"{size} bytes, more than the {MAX_MESH_FILE_BYTES} a mesh file may have")
    reader = _read_obj if path.suffix.lower() == ".obj" else _read_gltf
    try:
        parts, material, names, file_tangents = reader(path, node)
    except OSError as error:
        raise FileError(path, f"cannot read ({error.strerror or error})") from None
    except (KeyError, IndexError, TypeError, ValueError) as error:  # a value of the wrong JSON type or shape
        raise FileError(path, f"malformed {path.suffix.lower()} file ({type(error).__name__}: {error}); "
                              "re-export it") from None
    corners = np.concatenate(parts) if parts else np.zeros((0, VERTEX_FLOATS))
    if not len(corners):
        raise FileError(path, "has no triangles" + (f" under {node!r}" if node else ""))
    keep = _triangle_areas(corners) > 0
    dropped = int(np.count_nonzero(~keep))
    if not keep.any():
        raise FileError(path, f"all {len(keep)} triangles have zero area; expected a mesh with a surface")
    if dropped:
        log.warning(f"{path}: dropped {dropped} of {len(keep)} triangles with zero area (degenerate)")
        corners = corners.reshape(-1, 3, VERTEX_FLOATS)[keep].reshape(-1, VERTEX_FLOATS)
    vertices = corners.astype(np.float32)
    vertices.flags.writeable = False
    return MeshData(vertices, material, names, dropped, file_tangents)


def _triangle_areas(corners: np.ndarray) -> np.ndarray:
    p = corners[:, :3].reshape(-1, 3, 3)
    return np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)


def _check_finite(path: Path, what: str, data: np.ndarray) -> None:
    bad = ~np.isfinite(data).all(axis=-1)
    if bad.any():
        raise FileError(path, f"{int(bad.sum())} {what} are NaN or infinite (the first at index {int(np.argmax(bad))}); "
                              "expected finite numbers: repair or re-export the mesh")


def _check_count(path: Path, vertices: int) -> None:
    if vertices > MAX_MESH_VERTICES:
        raise FileError(path, f"{vertices} vertices ({vertices // 3} triangles), more than the {MAX_MESH_VERTICES} a "
                              "mesh may have; decimate it or split it into nodes")


def corner_vertices(path: Path, where: str, positions, uv, faces, normals=None, tangents=None) -> np.ndarray:
    """(3 * len(faces), 12) float64 corners of indexed triangles: ``uv`` in this module's convention (v = 0 the
    image's top row); flat normals where ``normals`` is None (glTF's rule for meshes without them); tangents
    from ``tangents`` (xyz, w: v-handedness in this module's convention) or generated (``vertex_tangents``).
    ``where`` names the part in messages."""
    positions, uv = np.asarray(positions, np.float64), np.asarray(uv, np.float64)
    faces = np.asarray(faces, np.int64).reshape(-1, 3)
    if len(faces) and (faces.min() < 0 or faces.max() >= len(positions)):
        raise FileError(path, f"{where}: triangle indices outside its {len(positions)} vertices; re-export the mesh")
    _check_finite(path, f"{where}: positions", positions)
    _check_finite(path, f"{where}: uvs", uv)
    p = positions[faces]
    face_normals = _unit(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]))
    if normals is None:
        corner_normals = np.repeat(face_normals, 3, axis=0)
    else:
        normals = np.asarray(normals, np.float64)
        _check_finite(path, f"{where}: normals", normals)
        corner_normals = _unit(normals[faces.ravel()])
        missing = np.linalg.norm(corner_normals, axis=1) == 0  # zero normals in the file: the face's
        corner_normals[missing] = np.repeat(face_normals, 3, axis=0)[missing]
    if tangents is None:
        t, w = vertex_tangents(positions, uv, faces)
        t, w = t[faces.ravel()], w[faces.ravel()]
    else:
        tangents = np.asarray(tangents, np.float64)
        _check_finite(path, f"{where}: tangents", tangents)
        t, w = tangents[faces.ravel(), :3], np.where(tangents[faces.ravel(), 3] < 0, -1.0, 1.0)
    t = t - corner_normals * np.einsum("ij,ij->i", t, corner_normals)[:, None]
    t = _unit(t)
    lost = np.linalg.norm(t, axis=1) == 0  # no uv gradient, or along the normal: any perpendicular will do
    if lost.any():
        t[lost] = _perpendicular(corner_normals[lost])
    return np.concatenate([p.reshape(-1, 3), corner_normals, t, w[:, None], uv[faces.ravel()]], axis=1)


def _perpendicular(n: np.ndarray) -> np.ndarray:
    """Unit vectors perpendicular to the unit vectors ``n``."""
    helper = np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    return _unit(np.cross(n, helper))


def vertex_tangents(positions: np.ndarray, uv: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-vertex tangents (n, 3, unnormalised) and handedness (n,) from the uv derivatives of the triangles
    around each indexed vertex: each triangle's dP/du and dP/dv (solved from its edges and uv edges) summed at its
    corners weighted by the triangle's area (Lengyel's method, area-weighted); w = +1 where the summed dP/dv lies
    on the side of cross(normal, tangent), else -1, the normal being the summed triangle normals. Triangles with
    no uv area add nothing."""
    p, t = positions[faces], uv[faces]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    d1, d2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    ok = np.abs(det) > 1e-20
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)[:, None]
    dp_du = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * inv
    dp_dv = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * inv
    face_normal = np.cross(e1, e2)
    weight = np.linalg.norm(face_normal, axis=1, keepdims=True)  # twice the triangle's area
    n = len(positions)
    tangent, bitangent, normal = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
    for corner in range(3):
        np.add.at(tangent, faces[:, corner], dp_du * weight)
        np.add.at(bitangent, faces[:, corner], dp_dv * weight)
        np.add.at(normal, faces[:, corner], face_normal)
    w = np.where(np.einsum("ij,ij->i", np.cross(normal, tangent), bitangent) < 0, -1.0, 1.0)
    return tangent, w


# --- glTF 2.0 ---------------------------------------------------------------------------------

_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_TYPE_SIZES = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
_MODE_NAMES = {0: "points", 1: "lines", 2: "line loop", 3: "line strip", 5: "triangle strip", 6: "triangle fan"}
_IMAGE_SUFFIXES = {"image/png": ".png", "image/jpeg": ".jpg"}


class _Gltf:
    """One glTF file's JSON and buffers; accessors read with bounds checks. Problems are FileErrors."""

    def __init__(self, path: Path):
        self.path = path
        data = path.read_bytes()
        binary = None
        if path.suffix.lower() == ".glb":
            doc_bytes, binary = self._glb_chunks(data)
        else:
            doc_bytes = data
        try:
            self.doc = json.loads(doc_bytes)
        except (UnicodeDecodeError, json.JSONDecodeError) as error:
            raise FileError(path, f"not a glTF file (its JSON does not parse: {error}); re-export it") from None
        if not isinstance(self.doc, dict):
            raise FileError(path, "not a glTF file (its JSON is no object); re-export it")
        version = str(self.doc.get("asset", {}).get("version", ""))
        if not version.startswith("2."):
            raise FileError(path, f"glTF version {version or 'missing'}; expected 2.0")
        self.binary = binary
        self._buffers: dict[int, bytes] = {}

    def _glb_chunks(self, data: bytes) -> tuple[bytes, bytes | None]:
        if len(data) < 20 or data[:4] != b"glTF":
            raise FileError(self.path, "not a GLB file (no 'glTF' magic at its start); expected binary glTF 2.0")
        version, length = np.frombuffer(data[4:12], "<u4")
        if version != 2:
            raise FileError(self.path, f"GLB version {version}; expected 2")
        if length > len(data):
            raise FileError(self.path, f"truncated: its header says {length} bytes, the file has {len(data)}")
        chunks, at = {}, 12
        while at + 8 <= length:
            size, kind = (int(x) for x in np.frombuffer(data[at:at + 8], "<u4"))
            if at + 8 + size > length:
                raise FileError(self.path, f"truncated: a chunk runs past the end of the file at byte {at}")
            chunks.setdefault(kind, data[at + 8:at + 8 + size])
            at += 8 + size + (-size % 4)
        if 0x4E4F534A not in chunks:
            raise FileError(self.path, "GLB without a JSON chunk; re-export it")
        return chunks[0x4E4F534A], chunks.get(0x004E4942)

    def list(self, key: str) -> list:
        value = self.doc.get(key, [])
        if not isinstance(value, list):
            raise FileError(self.path, f"its '{key}' is no array; re-export it")
        return value

    def item(self, key: str, index) -> dict:
        items = self.list(key)
        if not (isinstance(index, int) and 0 <= index < len(items) and isinstance(items[index], dict)):
            raise FileError(self.path, f"refers to {key}[{index}], which it does not have; re-export it")
        return items[index]

    def uri_bytes(self, uri: str, what: str) -> bytes:
        if uri.startswith("data:"):
            head, _, payload = uri.partition(",")
            if not head.endswith(";base64"):
                raise FileError(self.path, f"{what}: a data URI without base64; expected base64 data")
            return base64.b64decode(payload)
        file = (self.path.parent / unquote(uri)).resolve()
        if not file.is_file():
            raise FileError(self.path, f"{what}: file {uri!r} not found (looked for {file})")
        return file.read_bytes()

    def buffer(self, index: int) -> bytes:
        if index not in self._buffers:
            spec = self.item("buffers", index)
            if "uri" in spec:
                data = self.uri_bytes(spec["uri"], f"buffers[{index}]")
            elif index == 0 and self.binary is not None:
                data = self.binary
            else:
                raise FileError(self.path, f"buffers[{index}] has no data (no uri, no GLB binary chunk)")
            if len(data) < spec.get("byteLength", 0):
                raise FileError(self.path, f"buffers[{index}]: {len(data)} bytes, fewer than its byteLength "
                                           f"{spec.get('byteLength')}; the file is truncated")
            self._buffers[index] = data
        return self._buffers[index]

    def view_bytes(self, index: int) -> tuple[memoryview, int]:
        """A buffer view's bytes and its byteStride (0: tightly packed)."""
        view = self.item("bufferViews", index)
        data = self.buffer(view.get("buffer", -1))
        start, length = view.get("byteOffset", 0), view.get("byteLength", 0)
        if start + length > len(data):
            raise FileError(self.path, f"bufferViews[{index}] reads past the end of its buffer; re-export it")
        return memoryview(data)[start:start + length], view.get("byteStride", 0)

    def count(self, index: int) -> int:
        return int(self.item("accessors", index).get("count", 0))

    def accessor(self, index: int) -> np.ndarray:
        """Accessor ``index`` as float64 (count, components) (indices: int64 (count,)); normalized integers scaled
        to [0, 1] or [-1, 1] as glTF defines them."""
        spec = self.item("accessors", index)
        what = f"accessors[{index}]"
        if "sparse" in spec:
            raise FileError(self.path, f"{what} is sparse, which is not supported; re-export without sparse accessors")
        dtype = _COMPONENTS.get(spec.get("componentType"))
        width = _TYPE_SIZES.get(spec.get("type"))
        count = int(spec.get("count", 0))
        if dtype is None or width is None:
            raise FileError(self.path, f"{what}: componentType {spec.get('componentType')} / type {spec.get('type')} "
                                       "is not a glTF 2.0 accessor type; re-export it")
        item = np.dtype(dtype).itemsize * width
        if count > MAX_MESH_VERTICES:  # before anything of that size is made
            raise FileError(self.path, f"{what} has {count} elements, more than the {MAX_MESH_VERTICES} vertices a "
                                       "mesh may have; decimate it or split it into nodes")
        if "bufferView" not in spec:
            data = np.zeros((count, width), dtype)
        else:
            raw, stride = self.view_bytes(spec["bufferView"])
            stride = stride or item
            offset = spec.get("byteOffset", 0)
            if count and offset + stride * (count - 1) + item > len(raw):
                raise FileError(self.path, f"{what} reads past the end of its buffer view; re-export it")
            rows = np.lib.stride_tricks.as_strided(np.frombuffer(raw, np.uint8, offset=offset) if count else
                                                   np.zeros(item, np.uint8), (count, item), (stride, 1))
            data = np.ascontiguousarray(rows).view(np.dtype(dtype).newbyteorder("<")).reshape(count, width)
        if spec.get("normalized") and np.issubdtype(dtype, np.integer):
            info = np.iinfo(dtype)
            return np.maximum(data / info.max, -1.0)
        if spec.get("type") == "SCALAR" and np.issubdtype(dtype, np.integer):
            return data.reshape(-1).astype(np.int64)
        return data.astype(np.float64)

    def image_ref(self, texture_info, slot: str, where: str) -> TextureRef | None:
        """The TextureRef of a material's texture (``{"index": i}``): an external image file, or embedded bytes
        (a buffer view or data URI) written to the private image folder."""
        if not isinstance(texture_info, dict) or "index" not in texture_info:
            return None
        if texture_info.get("texCoord", 0) != 0:
            log.warning(f"{self.path}: {where} {slot} uses TEXCOORD_{texture_info['texCoord']}; read with TEXCOORD_0")
        texture = self.item("textures", texture_info["index"])
        source = texture.get("source")
        if source is None:
            raise FileError(self.path, f"{where}: textures[{texture_info['index']}] has no image source (an "
                                       "extension's image format?); expected a PNG or JPEG image")
        image = self.item("images", source)
        what = f"images[{source}] ({slot} of {where})"
        uri = image.get("uri")
        if uri is not None and not uri.startswith("data:"):
            file = (self.path.parent / unquote(uri)).resolve()
            if not file.is_file():
                raise FileError(self.path, f"{what}: file {uri!r} not found (looked for {file})")
        else:
            if uri is not None:
                data = self.uri_bytes(uri, what)
                mime = uri[5:].partition(";")[0]
            else:
                raw, _ = self.view_bytes(image.get("bufferView", -1))
                data, mime = bytes(raw), image.get("mimeType", "")
            if mime not in _IMAGE_SUFFIXES:
                raise FileError(self.path, f"{what}: image type {mime or 'unknown'}; expected image/png or image/jpeg")
            file = _embedded_image(data, _IMAGE_SUFFIXES[mime])
        try:
            read_header(file)
        except FileError as error:
            raise FileError(self.path, f"{what}: {error.reason}") from None
        return TextureRef("file", path=file, origin=f"{self.path}: {what}")


def _node_matrix(node: dict) -> np.ndarray:
    if "matrix" in node:
        return np.asarray(node["matrix"], np.float64).reshape(4, 4).T  # column-major in the file
    x, y, z, w = node.get("rotation", (0.0, 0.0, 0.0, 1.0))
    rotation = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    m = np.eye(4)
    m[:3, :3] = rotation * np.asarray(node.get("scale", (1.0, 1.0, 1.0)), np.float64)
    m[:3, 3] = node.get("translation", (0.0, 0.0, 0.0))
    return m


def _node_name(node: dict, index: int) -> str:
    return str(node.get("name") or f"node{index}")


def _read_gltf(path: Path, wanted: str | None):
    gltf = _Gltf(path)
    nodes = gltf.list("nodes")
    names = tuple(_node_name(n, i) if isinstance(n, dict) else f"node{i}" for i, n in enumerate(nodes))
    children = {c for n in nodes if isinstance(n, dict) for c in n.get("children", [])}
    scenes = gltf.list("scenes")
    roots = gltf.item("scenes", gltf.doc.get("scene", 0)).get("nodes", []) if scenes else \
        [i for i in range(len(nodes)) if i not in children]
    if wanted is not None:
        matches = [i for i, name in enumerate(names) if name == wanted]
        if not matches:
            raise NodeNotFound(path, f"no node named {wanted!r} in {path.name}; its nodes: {', '.join(names) or 'none'}")
        if len(matches) > 1:
            raise FileError(path, f"{len(matches)} nodes are named {wanted!r}; expected one (rename them)")
    # (node, world matrix) of every node with a mesh: below the roots, or below the wanted node (placed as the
    # file places it)
    placed, stack, seen = [], [(r, np.eye(4), wanted is None) for r in roots], set()
    while stack:
        index, parent, inside = stack.pop()
        node = gltf.item("nodes", index)
        if index in seen:
            raise FileError(path, f"nodes[{index}] is reached twice (a cycle or a shared child); re-export it")
        seen.add(index)
        world = parent @ _node_matrix(node)
        inside = inside or names[index] == wanted
        if inside and "mesh" in node:
            placed.append((node["mesh"], world, names[index]))
        stack.extend((c, world, inside) for c in node.get("children", []))
    if wanted is not None and not placed:
        raise NodeNotFound(path, f"node {wanted!r} has no mesh, nor have its children; its nodes: {', '.join(names)}")
    total = 0
    primitives = []
    for mesh_index, world, name in placed:
        for p, prim in enumerate(gltf.item("meshes", mesh_index).get("primitives", [])):
            where = f"node {name!r} mesh {mesh_index} primitive {p}"
            mode = prim.get("mode", 4)
            if mode != 4:
                raise FileError(path, f"{where}: {_MODE_NAMES.get(mode, f'mode {mode}')} are not supported; "
                                      "expected triangles (export triangulated)")
            attributes = prim.get("attributes", {})
            if "POSITION" not in attributes:
                raise FileError(path, f"{where}: no POSITION attribute; re-export it")
            if "TEXCOORD_0" not in attributes:
                raise FileError(path, f"{where}: no TEXCOORD_0 (uv) attribute; relief mapping needs uvs: unwrap the "
                                      "mesh and export it with uvs")
            total += gltf.count(prim["indices"]) if "indices" in prim else gltf.count(attributes["POSITION"])
            _check_count(path, total)
            primitives.append((prim, world, where))
    materials = [prim.get("material") for prim, *_ in primitives]
    used = [m for m in dict.fromkeys(materials) if m is not None]
    if len(used) > 1:
        log.warning(f"{path}: {len(used)} materials on the mesh{f' of node {wanted!r}' if wanted else ''}; the first "
                    f"one's textures are used for all of it (give each material its own node and object)")
    parts, tangents_used = [], []
    for prim, world, where in primitives:
        attributes = prim["attributes"]
        positions = gltf.accessor(attributes["POSITION"])
        faces = gltf.accessor(prim["indices"]) if "indices" in prim else np.arange(len(positions))
        if len(faces) % 3:
            raise FileError(path, f"{where}: {len(faces)} indices, not a multiple of 3; re-export it")
        normals = gltf.accessor(attributes["NORMAL"]) if "NORMAL" in attributes else None
        tangents = gltf.accessor(attributes["TANGENT"]) if "TANGENT" in attributes and normals is not None else None
        if tangents is not None:
            tangents = tangents.copy()
            tangents[:, 3] *= -1  # glTF's bitangent points to image row 0 (its normal maps' +Y); ours to +v
        tangents_used.append(tangents is not None)
        local = corner_vertices(path, where, positions[:, :3], gltf.accessor(attributes["TEXCOORD_0"])[:, :2],
                                faces, normals, tangents)
        parts.append(transformed(local, world[:3, :3], world[:3, 3]))
    material = _gltf_material(gltf, used[0]) if used else None
    return parts, material, names, bool(tangents_used) and all(tangents_used)


def _gltf_material(gltf: _Gltf, index: int) -> FileMaterial:
    spec = gltf.item("materials", index)
    where = f"materials[{index}]"
    name = str(spec.get("name") or where)
    pbr = spec.get("pbrMetallicRoughness", {})
    factor = pbr.get("baseColorFactor", [1.0, 1.0, 1.0, 1.0])
    albedo = gltf.image_ref(pbr.get("baseColorTexture"), "baseColorTexture", where)
    if albedo is not None and any(abs(c - 1.0) > 1e-6 for c in factor[:3]):
        log.warning(f"{gltf.path}: {where} baseColorFactor {factor[:3]} is not applied to its baseColorTexture")
    normal = gltf.image_ref(spec.get("normalTexture"), "normalTexture", where)
    color = tuple(float(np.clip(c, 0.0, 1.0)) for c in factor[:3])
    return FileMaterial(name, albedo=albedo, color=color, normal=normal)


# --- embedded images --------------------------------------------------------------------------

_IMAGE_FOLDER: list[Path] = []


def _embedded_image(data: bytes, suffix: str) -> Path:
    """A file holding an embedded image's bytes (named by their sha256), in a private folder removed at exit."""
    if not _IMAGE_FOLDER:
        folder = Path(tempfile.mkdtemp(prefix="wgpuviewer-mesh-images-"))
        atexit.register(shutil.rmtree, folder, True)
        _IMAGE_FOLDER.append(folder)
    file = _IMAGE_FOLDER[0] / (hashlib.sha256(data).hexdigest() + suffix)
    if not file.exists():
        temp = file.with_name(file.name + ".tmp")
        temp.write_bytes(data)
        temp.replace(file)
    return file


# --- Wavefront OBJ ----------------------------------------------------------------------------


def _read_obj(path: Path, wanted: str | None):
    from trimesh.exchange.obj import load_obj  # trimesh takes 0.6 s to import: only a scene with an OBJ pays it
    from trimesh.geometry import triangulate_quads

    text = path.read_bytes()
    try:
        loaded = load_obj(io.BytesIO(text), skip_materials=True, split_objects=True, group_material=False)
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
        _check_count(path, total)
        visual = part.get("visual")
        uv = getattr(visual, "uv", None)
        if uv is None or len(uv) != len(part["vertices"]):
            raise FileError(path, f"object {name!r} has no uvs (vt); relief mapping needs uvs: unwrap the mesh and "
                                  "export it with uvs")
        uv = np.asarray(uv, np.float64).copy()
        uv[:, 1] = 1.0 - uv[:, 1]  # OBJ's vt has v up from the image's bottom row; ours starts at its top row
        parts.append(corner_vertices(path, f"object {name!r}", part["vertices"], uv, faces,
                                     part.get("vertex_normals")))
    return parts, _obj_material(path, text.decode("utf-8", "replace")), names, False


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
        mtl = (path.parent / library).resolve()
        if not mtl.is_file():
            raise FileError(path, f"mtllib {library!r} not found (looked for {mtl})")
        statements: dict[str, dict[str, str]] = {}
        current = None
        for line in mtl.read_text(encoding="utf-8", errors="replace").splitlines():
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
        file = (mtl.parent / file_name).resolve()
        what = f"{mtl.name}: material {name!r} {key} {file_name!r}"
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


def clear_cache() -> None:
    """Forget loaded meshes (between tests)."""
    _load_mesh.cache_clear()
