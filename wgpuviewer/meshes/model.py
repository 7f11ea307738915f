"""What a mesh file gives (``MeshData``, ``FileMaterial``), the limits every mesh file is read under, and
``NodeNotFound``: the types the glTF and OBJ readers and ``files`` share."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer.core.errors import FileError
from wgpuviewer.textures import TextureRef

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


def check_count(path: Path, vertices: int) -> None:
    if vertices > MAX_MESH_VERTICES:
        raise FileError(path, f"{vertices} vertices ({vertices // 3} triangles), more than the {MAX_MESH_VERTICES} a "
                              "mesh may have; decimate it or split it into nodes")
