"""The window's keyboard, pointer and wheel events as viewer actions: a key press goes to ``Viewer.press``
(``keys.CONTROLS``), the fly keys are held and move the fly camera each frame, a left drag turns the camera or
moves the A/B divider, the wheel zooms the orbit camera or changes the fly speed. A scripted run holds fly keys
through ``hold``."""

from __future__ import annotations

import numpy as np

from .keys import FLY_KEYS
from .settings import LIMITS


class Input:
    def __init__(self, viewer):
        self.viewer = viewer
        self.held: set[str] = set()
        self.scripted: list[tuple[str, float]] = []  # (fly key, seconds) for the next frame
        self.told_orbit = False
        self.drag_from: tuple[float, float] | None = None
        self.dragging_divider = False
        window = viewer.window
        window.on(self.on_key_down, "key_down")
        window.on(self.on_key_up, "key_up")
        window.on(self.on_pointer, "pointer_down", "pointer_up", "pointer_move")
        window.on(self.on_wheel, "wheel")

    def hold(self, key: str, seconds: float) -> None:
        """A scripted run's fly key (``keys.ScriptStep``): held through the next frame, moving the camera by
        ``seconds`` of motion whatever that frame takes."""
        self.scripted.append((key, seconds))
        if self.viewer.camera_mode != "fly" and not self.told_orbit:
            self.told_orbit = True
            self.viewer.message(f"--keys {key.upper()}: the fly keys move the fly camera; the orbit camera is on "
                                "(O switches)")

    def fly(self, dt: float) -> None:
        """Move the fly camera by the held keys for ``dt`` seconds, and by the scripted holds for theirs."""
        v = self.viewer
        moves = [(key, dt) for key in self.held] + self.scripted
        self.scripted = []
        if moves and v.camera_mode == "fly":
            v.fly.move(*(np.sum([np.multiply(FLY_KEYS[k], s) for k, s in moves], axis=0) * v.move_speed))

    def on_key_down(self, event):
        key = event["key"]
        if key in FLY_KEYS:
            self.held.add(key)
        else:
            self.viewer.press(key)

    def on_key_up(self, event):
        self.held.discard(event["key"].lower())  # Shift released first: "D" ends the held "d"

    def _divider_hit(self, x: float) -> bool:
        width = self.viewer.window.logical_size()[0]
        return self.viewer.state.split and abs(x - self.viewer.state.split_x * width) <= 8

    def on_pointer(self, event):
        kind = event["event_type"]
        if kind == "pointer_down" and event["button"] == 1:
            if self._divider_hit(event["x"]):
                self.dragging_divider = True
            else:
                self.drag_from = (event["x"], event["y"])
        elif kind == "pointer_up":
            self.drag_from = None
            self.dragging_divider = False
        elif kind == "pointer_move":
            if self.dragging_divider:
                width = max(self.viewer.window.logical_size()[0], 1)
                self.viewer.state.split_x = float(np.clip(event["x"] / width, 0.02, 0.98))
            elif self.drag_from is not None:
                self.viewer.cam.look(event["x"] - self.drag_from[0], event["y"] - self.drag_from[1])
                self.drag_from = (event["x"], event["y"])

    def on_wheel(self, event):
        steps = event["dy"] / 100.0
        if self.viewer.camera_mode == "orbit":
            self.viewer.orbit.zoom(steps)
        else:
            lo, hi = LIMITS["move_speed"]
            self.viewer.move_speed = float(np.clip(self.viewer.move_speed * 1.1 ** (-steps), lo, hi))

