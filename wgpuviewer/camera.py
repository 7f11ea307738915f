"""Camera and transform maths (right-handed, +Y up, WebGPU clip depth in [0, 1]).

Matrices are row-major numpy float64 here; ``to_wgsl`` transposes them into WGSL's column-major layout.
"""

from __future__ import annotations

import numpy as np


def normalize(v) -> np.ndarray:
    v = np.asarray(v, np.float64)
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


def look_at(eye, target, up) -> np.ndarray:
    eye, target = np.asarray(eye, np.float64), np.asarray(target, np.float64)
    forward = normalize(target - eye)
    right = np.cross(forward, up)
    if np.linalg.norm(right) < 1e-9:  # looking along `up`: any perpendicular will do
        right = np.cross(forward, [0.0, 0.0, 1.0] if abs(forward[2]) < 0.9 else [1.0, 0.0, 0.0])
    right = normalize(right)
    true_up = np.cross(right, forward)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = right, true_up, -forward
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def perspective(fov_y_deg: float, aspect: float, near: float, far: float) -> np.ndarray:
    """Reversed-Z projection: depth 1 at ``near``, 0 at ``far`` (the renderer clears depth to 0 and keeps the
    greater). Depth is then about near / distance, which float32 holds with the same relative precision at any
    distance, so a tiny ``near`` (1e-9) still separates surfaces (standard depth would round to 1 everywhere)."""
    f = 1.0 / np.tan(np.radians(fov_y_deg) / 2.0)
    m = np.zeros((4, 4))
    m[0, 0] = f / aspect
    m[1, 1] = f
    m[2, 2] = near / (far - near)
    m[2, 3] = near * far / (far - near)
    m[3, 2] = -1.0
    return m


def rotation_xyz(degrees) -> np.ndarray:
    """Euler rotation, X first, then Y, then Z (4x4)."""
    rx, ry, rz = np.radians(np.asarray(degrees, np.float64))
    cx, sx, cy, sy, cz, sz = np.cos(rx), np.sin(rx), np.cos(ry), np.sin(ry), np.cos(rz), np.sin(rz)
    x = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    y = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    z = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    m = np.eye(4)
    m[:3, :3] = z @ y @ x
    return m


def translation(offset) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = offset
    return m


def to_wgsl(m: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(m, np.float32).T)
