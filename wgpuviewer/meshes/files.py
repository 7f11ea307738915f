"""Mesh files: ``load_mesh`` reads a glTF 2.0 (``gltf``) or Wavefront OBJ (``obj``) file once per file, node,
size and modification time, drops zero-area triangles, and gives its ``MeshData``; ``for_object`` gives a scene
object's vertices, a builtin shape's or a mesh file's."""

from __future__ import annotations

import logging
from functools import lru_cache
from pathlib import Path

import numpy as np

from wgpuviewer.core.errors import FileError

from . import model
from .gltf import read_gltf
from .model import MESH_SUFFIXES, MeshData
from .obj import read_obj
from .shapes import build
from .tangents import VERTEX_FLOATS, transformed

log = logging.getLogger("wgpuviewer.meshes")


def for_object(obj) -> np.ndarray:
    """The vertices of a scene object (``scene.SceneObject``), in this module's layout: a builtin shape of its
    ``size``, or a mesh file's (``load_mesh``) scaled by its ``scale``."""
    if obj.type == "mesh":
        mesh = load_mesh(obj.file, obj.node)
        return transformed(mesh.vertices, np.diag(obj.scale)).astype(np.float32)
    return build(obj.type, obj.size)


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
    if size > model.MAX_MESH_FILE_BYTES:
        raise FileError(path, f"{size} bytes, more than the {model.MAX_MESH_FILE_BYTES} a mesh file may have")
    reader = read_obj if path.suffix.lower() == ".obj" else read_gltf
    try:
        parts, material, names, file_tangents = reader(path, node)
    except OSError as error:
        raise FileError(path, f"cannot read ({error.strerror or error})") from None
    except (KeyError, IndexError, TypeError, ValueError) as error:  # what the readers' own checks did not name
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


def clear_cache() -> None:
    """Forget loaded meshes (between tests)."""
    _load_mesh.cache_clear()
