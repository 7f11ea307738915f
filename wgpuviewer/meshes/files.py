"""Mesh files: ``load_mesh`` reads a glTF 2.0 (``gltf``) or Wavefront OBJ (``obj``) file once per file, node,
size and modification time (again when its material is wanted and was not read), checks the surface it gives in
float32 (what the GPU draws: positions within float32's range, zero-area triangles dropped, and when none is left
the reason named) and gives its ``MeshData``; ``for_object`` gives a scene object's vertices, a builtin shape's or
a mesh file's. A load taking more than a second shows a progress bar on a terminal
(``core.commands.terminal_progress``)."""

from __future__ import annotations

import logging
import threading
from collections import OrderedDict
from pathlib import Path

import numpy as np

from wgpuviewer.core.commands import terminal_progress
from wgpuviewer.core.errors import FileError

from . import model
from .gltf import FLOAT32_MAX, read_gltf
from .model import MESH_SUFFIXES, MeshData
from .obj import read_obj
from .shapes import build
from .tangents import VERTEX_FLOATS, transformed, triangle_areas

log = logging.getLogger("wgpuviewer.meshes")

#: Meshes kept (``load_mesh``): the last ones read.
CACHED_MESHES = 16
#: (path, node, modification time, size) -> (MeshData, whether its material was read), most recent last.
_CACHE: OrderedDict[tuple, tuple[MeshData, bool]] = OrderedDict()
#: Guards ``_CACHE`` (renders may run in several threads); a mesh is read outside it.
_CACHE_LOCK = threading.Lock()



def for_object(obj) -> np.ndarray:
    """The vertices of a scene object (``scene.SceneObject``), in this module's layout: a builtin shape of its
    ``size``, or a mesh file's (``load_mesh``) scaled by its ``scale``."""
    if obj.type == "mesh":
        mesh = load_mesh(obj.file, obj.node, material=False)
        return transformed(mesh.vertices, np.diag(obj.scale)).astype(np.float32)
    return build(obj.type, obj.size)


def load_mesh(path: Path, node: str | None = None, material: bool = True) -> MeshData:
    """The mesh of file ``path`` (glTF 2.0 or OBJ), all of it or the node/object named ``node`` with its children;
    its own material read (and its textures checked) only where ``material`` (a scene that gives the object a
    material of its own does not need the file's, so a missing ``.mtl`` or a damaged embedded image is no error).
    Read once per file, node, size and modification time. Raises FileError (reason: what is wrong, the fix)."""
    path = Path(path)
    try:
        stat = path.stat()
    except OSError as error:
        raise FileError(path, f"cannot read ({error.strerror or error})") from None
    key = (path, node, stat.st_mtime_ns, stat.st_size)
    with _CACHE_LOCK:
        cached = _CACHE.get(key)
    if cached is None or (material and not cached[1]):
        cached = (_load_mesh(path, node, stat.st_size, material), material)
    with _CACHE_LOCK:
        if material or key not in _CACHE:  # never replace an entry with its material by one without
            _CACHE[key] = cached
        _CACHE.move_to_end(key)
        while len(_CACHE) > CACHED_MESHES:
            _CACHE.popitem(last=False)
    return cached[0]


def _load_mesh(path: Path, node: str | None, size: int, material: bool) -> MeshData:
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise FileError(path, f"unsupported mesh file type {path.suffix!r}; expected {', '.join(MESH_SUFFIXES)}")
    if not path.is_file():
        raise FileError(path, "not a file; expected a mesh file")
    if size > model.MAX_MESH_FILE_BYTES:
        raise FileError(path, f"{size} bytes, more than the {model.MAX_MESH_FILE_BYTES} a mesh file may have")
    reader = read_obj if path.suffix.lower() == ".obj" else read_gltf
    with terminal_progress(f"reading {path.name}", unit="step") as progress:
        progress("parsing", 0, 2)
        try:
            with np.errstate(all="ignore"):  # what overflows in a hostile file's numbers is checked below, by name
                parts, file_material, names, file_tangents = reader(path, node, material)
        except OSError as error:
            raise FileError(path, f"cannot read ({error.strerror or error})") from None
        except (KeyError, IndexError, TypeError, ValueError) as error:  # what the readers' own checks did not name
            raise FileError(path, f"malformed {path.suffix.lower()} file ({type(error).__name__}: {error}); "
                                  "re-export it") from None
        progress("checking triangles", 1, 2)
        corners = np.concatenate(parts) if parts else np.zeros((0, VERTEX_FLOATS))
        if not len(corners):
            raise FileError(path, "has no triangles" + (f" under {node!r}" if node else ""))
        vertices, dropped = _surface(path, corners)
        progress("done", 2, 2)
    return MeshData(vertices, file_material, names, dropped, file_tangents)


def _surface(path: Path, corners: np.ndarray) -> tuple[np.ndarray, int]:
    """(read-only float32 vertices without their zero-area triangles, how many were dropped) of float64 corners;
    the area is measured on the float32 positions the GPU draws. When no triangle is left, the reason is named:
    degenerate triangles, or positions too far from the origin for float32 to keep their corners apart."""
    reach = float(np.max(np.abs(corners[:, :3])))
    if not reach <= FLOAT32_MAX:
        raise FileError(path, f"positions reach {reach:.3g} (node transforms applied), beyond float32's range "
                              f"({FLOAT32_MAX:.3g}); re-export it in smaller units or nearer the origin")
    with np.errstate(all="ignore"):
        vertices = corners.astype(np.float32)
    _check_finite(path, vertices)
    keep = triangle_areas(vertices) > 0
    dropped = int(np.count_nonzero(~keep))
    if not keep.any():
        if (triangle_areas(corners) > 0).any():
            extent = float(np.max(np.ptp(corners[:, :3], axis=0)))
            raise FileError(path, f"its {len(keep)} triangles ({extent:.3g} across) lie {reach:.3g} from the origin, "
                                  "too far for float32 to keep their corners apart; move the mesh nearer the origin "
                                  "(re-export it centred, or drop the node's translation)")
        raise FileError(path, f"all {len(keep)} triangles have zero area (the corners of each lie on one line or "
                              "point); expected a mesh with a surface")
    if dropped:
        log.warning(f"{path}: dropped {dropped} of {len(keep)} triangles with zero area (degenerate)")
        vertices = vertices.reshape(-1, 3, VERTEX_FLOATS)[keep].reshape(-1, VERTEX_FLOATS)
    vertices.flags.writeable = False
    return vertices, dropped


#: Vertex columns (``tangents`` layout) by the name messages give them.
_COLUMNS = {"uvs": slice(10, 12), "normals": slice(3, 6), "tangents": slice(6, 10)}  # uvs first: tangents follow them


def _check_finite(path: Path, vertices: np.ndarray) -> None:
    """Every normal, tangent and uv finite in float32 (the file's numbers are checked as read; what a node
    transform or a texture transform made of them is checked here), or a FileError naming the column."""
    for name, columns in _COLUMNS.items():
        bad = ~np.isfinite(vertices[:, columns]).all(axis=1)
        if bad.any():
            cause = "the material's texture transform" if name == "uvs" else "the node transforms"
            raise FileError(path, f"{int(bad.sum())} {name} are NaN or beyond float32's range after {cause} (the first "
                                  f"at corner {int(np.argmax(bad))}); re-export it with sensible transforms")


def clear_cache() -> None:
    """Forget loaded meshes (between tests)."""
    with _CACHE_LOCK:
        _CACHE.clear()
