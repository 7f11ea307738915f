"""The viewer's cameras: fly (position + yaw/pitch, WASD/QE and drag) and orbit (around the scene camera's
target: drag turns, the wheel zooms). Both start from, and reset to, the scene's camera."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from wgpuviewer.camera import normalize
from wgpuviewer.scene import Camera

LOOK_SPEED = 0.005  # radians per pixel dragged (default; settings.look_sensitivity)


class _SceneCamera:
    """A camera started from (and reset to) the scene's camera ``start``, turned at ``sensitivity`` radians per
    pixel dragged."""

    def __init__(self, camera: Camera, sensitivity: float = LOOK_SPEED):
        self.start = camera
        self.sensitivity = sensitivity
        self.reset()

    def reset(self):
        raise NotImplementedError

    @staticmethod
    def pitch_of(direction: np.ndarray) -> float:
        """The pitch of a unit direction: its angle above the horizontal plane."""
        return float(np.arcsin(np.clip(direction[1], -1.0, 1.0)))


class FlyCamera(_SceneCamera):
    """Position + yaw/pitch, started from (and reset to) the scene's camera."""

    def reset(self):
        self.position = np.asarray(self.start.position, np.float64)
        forward = normalize(np.asarray(self.start.target, np.float64) - self.position)
        self.yaw = float(np.arctan2(forward[0], -forward[2]))
        self.pitch = self.pitch_of(forward)

    @property
    def forward(self) -> np.ndarray:
        cp = np.cos(self.pitch)
        return np.array([np.sin(self.yaw) * cp, np.sin(self.pitch), -np.cos(self.yaw) * cp])

    def look(self, dx: float, dy: float):
        self.yaw += dx * self.sensitivity
        self.pitch = float(np.clip(self.pitch - dy * self.sensitivity, -1.55, 1.55))

    def move(self, right: float, up: float, forward: float):
        f = self.forward
        r = normalize(np.cross(f, [0.0, 1.0, 0.0]))
        self.position = self.position + r * right + np.array([0.0, 1.0, 0.0]) * up + f * forward

    def camera(self) -> Camera:
        p = self.position
        return replace(self.start, position=tuple(p), target=tuple(p + self.forward), up=(0.0, 1.0, 0.0))


class OrbitCamera(_SceneCamera):
    """Orbits the scene camera's target: drag turns, the wheel zooms (distance factor per step)."""

    MIN_DISTANCE = 0.05

    def __init__(self, camera: Camera, sensitivity: float = LOOK_SPEED, zoom: float = 0.1):
        self.zoom_step = zoom
        super().__init__(camera, sensitivity)

    def reset(self):
        self.target = np.asarray(self.start.target, np.float64)
        offset = np.asarray(self.start.position, np.float64) - self.target
        self.distance = max(float(np.linalg.norm(offset)), self.MIN_DISTANCE)
        d = offset / self.distance if np.linalg.norm(offset) > 0 else np.array([0.0, 0.0, 1.0])
        self.yaw = float(np.arctan2(d[0], d[2]))
        self.pitch = self.pitch_of(d)

    def look(self, dx: float, dy: float):
        self.yaw -= dx * self.sensitivity
        self.pitch = float(np.clip(self.pitch + dy * self.sensitivity, -1.55, 1.55))

    def zoom(self, steps: float):
        """Positive steps move away, negative closer (multiplicative, never through the target)."""
        self.distance = float(
            np.clip(self.distance * (1.0 + self.zoom_step) ** steps, self.MIN_DISTANCE, self.start.far * 0.9)
        )

    @property
    def position(self) -> np.ndarray:
        cp = np.cos(self.pitch)
        return self.target + self.distance * np.array([np.sin(self.yaw) * cp, np.sin(self.pitch), np.cos(self.yaw) * cp])

    def camera(self) -> Camera:
        return replace(self.start, position=tuple(self.position), target=tuple(self.target), up=(0.0, 1.0, 0.0))
