"""The builtin shapes, in the vertex layout of ``tangents``: plane, quad and box (flat faces), and the curved
sphere, cylinder and torus (parametric surfaces with analytic normals and tangents). Every shape is a non-indexed
triangle list, front faces counter-clockwise seen from outside; ``BUILTIN_SHAPES`` names each one's size keys and
``DEFAULT_SIZES`` gives the size a scene may leave out."""

from __future__ import annotations

import numpy as np


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


#: Builtin object type -> (its size keys, documented in order, its vertex builder).
BUILTIN_SHAPES = {
    "plane": (("width", "depth"), plane),
    "quad": (("width", "height"), quad),
    "box": (("x", "y", "z"), box),
    "sphere": (("radius",), sphere),
    "cylinder": (("radius", "height"), cylinder),
    "torus": (("major radius", "minor radius"), torus),
}


#: Builtin object type -> its size where a scene gives none: each shape filling a cube of side 1 around its origin.
DEFAULT_SIZES = {
    "plane": (1.0, 1.0),
    "quad": (1.0, 1.0),
    "box": (1.0, 1.0, 1.0),
    "sphere": (0.5,),
    "cylinder": (0.5, 1.0),
    "torus": (0.35, 0.15),
}


def build(object_type: str, size) -> np.ndarray:
    if object_type not in BUILTIN_SHAPES:
        raise ValueError(f"unknown mesh kind {object_type!r}")
    return BUILTIN_SHAPES[object_type][1](*size)
