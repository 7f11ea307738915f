"""Meshes with tangent frames: the builtin shapes and meshes read from glTF 2.0 (``.gltf``, ``.glb``) and Wavefront
OBJ files, one module per job:

- ``tangents``: the vertex layout (48 bytes: position, normal, tangent xyzw, uv), tangent frames of indexed
  triangles (from the file or generated), transforms that keep frames and front faces;
- ``shapes``: plane, quad, box and the curved sphere, cylinder and torus (``BUILTIN_SHAPES``, ``DEFAULT_SIZES``,
  ``build``);
- ``model``: what a mesh file gives (``MeshData``, ``FileMaterial``), the limits files are read under,
  ``NodeNotFound``;
- ``gltf_document``: a glTF file parsed by pygltflib, its GLB framing and JSON types checked first, required
  extensions we do not implement refused; ``gltf_accessors``: its buffers and accessors, every number checked
  before it is used; ``gltf``: nodes, primitives and the material's images (embedded ones as bytes);
- ``obj``: OBJ through trimesh (its text decoded and its faces counted against the limit first), its ``.mtl``
  material;
- ``files``: ``load_mesh`` (once per file, node and modification time) and ``for_object``.

Every mesh is a non-indexed triangle list, front faces counter-clockwise seen from outside.

May import: ``wgpuviewer.core`` and the other scene modules (``textures``: a file's textures are TextureRefs).
"""

from .files import clear_cache, for_object, load_mesh
from .model import MAX_MESH_FILE_BYTES, MAX_MESH_VERTICES, MESH_SUFFIXES, FileMaterial, MeshData, NodeNotFound
from .shapes import (
    BUILTIN_SHAPES,
    CYLINDER_SEGMENTS,
    DEFAULT_SIZES,
    SPHERE_GRID,
    TORUS_GRID,
    box,
    build,
    cylinder,
    plane,
    quad,
    sphere,
    torus,
)
from .tangents import VERTEX_ATTRIBUTES, VERTEX_FLOATS, VERTEX_STRIDE, corner_vertices, transformed, vertex_tangents

__all__ = [
    "BUILTIN_SHAPES", "CYLINDER_SEGMENTS", "DEFAULT_SIZES", "MAX_MESH_FILE_BYTES", "MAX_MESH_VERTICES", "MESH_SUFFIXES",
    "SPHERE_GRID", "TORUS_GRID", "VERTEX_ATTRIBUTES", "VERTEX_FLOATS", "VERTEX_STRIDE", "FileMaterial", "MeshData",
    "NodeNotFound", "box", "build", "clear_cache", "corner_vertices", "cylinder", "for_object", "load_mesh", "plane", "quad",
    "sphere", "torus", "transformed", "vertex_tangents",
]
