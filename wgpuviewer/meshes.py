"""Meshes with tangent frames: plane, quad, box.

Vertex layout (48 bytes): position xyz, normal xyz, tangent xyzw (w = bitangent handedness), uv.
u runs along the tangent, v along the bitangent; image row 0 is v = 0.
"""

from __future__ import annotations

import numpy as np

VERTEX_STRIDE = 48
VERTEX_ATTRIBUTES = [
    {"format": "float32x3", "offset": 0, "shader_location": 0},
    {"format": "float32x3", "offset": 12, "shader_location": 1},
    {"format": "float32x4", "offset": 24, "shader_location": 2},
    {"format": "float32x2", "offset": 40, "shader_location": 3},
]


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


def build(kind: str, size) -> np.ndarray:
    if kind == "plane":
        return plane(*size)
    if kind == "quad":
        return quad(*size)
    if kind == "box":
        return box(*size)
    raise ValueError(f"unknown mesh kind {kind!r}")


def for_object(obj) -> np.ndarray:
    """The vertices of a scene object (``scene.SceneObject``), in this module's layout."""
    return build(obj.kind, obj.size)
