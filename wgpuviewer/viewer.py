"""The interactive window: rendercanvas (glfw) on any wgpu backend.

Keys: 1-9 pick a technique of the scene, Left/Right cycle, WASD/QE fly, drag with the left mouse
button to look around, R resets the camera, D toggles the cost view, Escape closes.
Scripted runs (tests, demos): ``frames`` frames, ``keys`` pressed one per frame, the last frame saved
to ``screenshot``.
"""

from __future__ import annotations

import logging
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from .camera import normalize
from .errors import UserError
from .gpu import get_gpu
from .output import save_rgb_png
from .renderer import DEPTH_FORMAT, Renderer
from .scene import Camera, Scene

MOVE_SPEED = 1.5  # scene units per second
LOOK_SPEED = 0.005  # radians per pixel dragged


class FlyCamera:
    """Position + yaw/pitch, started from (and reset to) the scene's camera."""

    def __init__(self, camera: Camera):
        self.start = camera
        self.reset()

    def reset(self):
        c = self.start
        self.position = np.asarray(c.position, np.float64)
        forward = normalize(np.asarray(c.target, np.float64) - self.position)
        self.yaw = float(np.arctan2(forward[0], -forward[2]))
        self.pitch = float(np.arcsin(np.clip(forward[1], -1.0, 1.0)))

    @property
    def forward(self) -> np.ndarray:
        cp = np.cos(self.pitch)
        return np.array([np.sin(self.yaw) * cp, np.sin(self.pitch), -np.cos(self.yaw) * cp])

    def look(self, dx: float, dy: float):
        self.yaw += dx * LOOK_SPEED
        self.pitch = float(np.clip(self.pitch - dy * LOOK_SPEED, -1.55, 1.55))

    def move(self, right: float, up: float, forward: float):
        f = self.forward
        r = normalize(np.cross(f, [0.0, 1.0, 0.0]))
        self.position = self.position + r * right + np.array([0.0, 1.0, 0.0]) * up + f * forward

    def camera(self) -> Camera:
        p = self.position
        return replace(self.start, position=tuple(p), target=tuple(p + self.forward), up=(0.0, 1.0, 0.0))


_MOVE_KEYS = {"w": (0, 0, 1), "s": (0, 0, -1), "a": (-1, 0, 0), "d_move": (1, 0, 0), "e": (0, 1, 0), "q": (0, -1, 0)}


class Viewer:
    def __init__(self, scene: Scene, technique: str, backend: str | None):
        try:
            from rendercanvas.glfw import RenderCanvas, loop
        except ImportError as error:
            raise UserError(
                f"the window needs glfw ({error}); install it with: pip install 'wgpuviewer[window]'"
            ) from None
        self.loop = loop
        self.scene = scene
        self.gpu = get_gpu(backend)
        self.renderer = Renderer(scene, self.gpu)
        self.techniques = list(scene.techniques)
        if technique not in self.techniques:
            self.techniques.append(technique)
        self.technique = technique
        self.mode = "color"
        self.fly = FlyCamera(scene.camera)
        self.held: set[str] = set()
        self.drag_from: tuple[float, float] | None = None
        self.canvas = RenderCanvas(title="wgpuviewer", size=(1280, 720), update_mode="continuous", max_fps=60)
        self.context = self.canvas.get_wgpu_context()
        self.format = self.context.get_preferred_format(self.gpu.adapter)
        # COPY_SRC lets a scripted run read back the frame it just drew.
        self.context.configure(device=self.gpu.device, format=self.format, usage="RENDER_ATTACHMENT|COPY_SRC")
        self._depth = None
        self._last_time = time.perf_counter()
        self.canvas.add_event_handler(self.on_key_down, "key_down")
        self.canvas.add_event_handler(self.on_key_up, "key_up")
        self.canvas.add_event_handler(self.on_pointer, "pointer_down", "pointer_up", "pointer_move")
        self._update_title()

    # --- input -------------------------------------------------------------------------------

    def press(self, key: str):
        """What a key does (also used by scripted runs)."""
        lower = key.lower()
        if key.isdigit() and 1 <= int(key) <= len(self.techniques):
            self.technique = self.techniques[int(key) - 1]
        elif key in ("ArrowRight", "ArrowLeft"):
            step = 1 if key == "ArrowRight" else -1
            self.technique = self.techniques[(self.techniques.index(self.technique) + step) % len(self.techniques)]
        elif lower == "r":
            self.fly.reset()
        elif key == "D":  # shift+d; plain d strafes
            self.mode = "cost" if self.mode == "color" else "color"
        elif key == "Escape":
            self.canvas.close()
        self._update_title()

    def on_key_down(self, event):
        key = event["key"]
        lower = key.lower()
        if lower in "wsaeq" and len(lower) == 1:
            self.held.add(lower)
        elif key == "d":
            self.held.add("d_move")
        else:
            self.press(key)

    def on_key_up(self, event):
        key = event["key"].lower()
        self.held.discard("d_move" if key == "d" else key)

    def on_pointer(self, event):
        kind = event["event_type"]
        if kind == "pointer_down" and event["button"] == 1:
            self.drag_from = (event["x"], event["y"])
        elif kind == "pointer_up":
            self.drag_from = None
        elif kind == "pointer_move" and self.drag_from is not None:
            self.fly.look(event["x"] - self.drag_from[0], event["y"] - self.drag_from[1])
            self.drag_from = (event["x"], event["y"])

    def _update_title(self):
        self.canvas.set_title(f"wgpuviewer - {self.scene.name} - {self.technique} ({self.mode})")

    # --- frames ------------------------------------------------------------------------------

    def draw(self) -> np.ndarray | None:
        now = time.perf_counter()
        dt, self._last_time = min(now - self._last_time, 0.1), now
        if self.held:
            step = np.sum([_MOVE_KEYS[k] for k in self.held], axis=0) * MOVE_SPEED * dt
            self.fly.move(*step)
        texture = self.context.get_current_texture()
        w, h = texture.size[:2]
        device = self.gpu.device
        if self._depth is None or self._depth.size[:2] != (w, h):
            self._depth = device.create_texture(
                label="window:depth", size=(w, h, 1), format=DEPTH_FORMAT, usage="RENDER_ATTACHMENT"
            )
        encoder = device.create_command_encoder(label="window")
        self.renderer.encode(
            encoder, [texture.create_view()], self._depth.create_view(), (self.format,),
            self.technique, self.fly.camera(), (w, h), self.mode,
        )
        device.queue.submit([encoder.finish()])
        return texture

    def read_frame(self, texture) -> np.ndarray:
        w, h = texture.size[:2]
        raw = self.gpu.device.queue.read_texture(
            {"texture": texture, "mip_level": 0, "origin": (0, 0, 0)},
            {"offset": 0, "bytes_per_row": w * 4, "rows_per_image": h},
            (w, h, 1),
        )
        pixels = np.frombuffer(raw, np.uint8).reshape(h, w, 4)
        rgb = pixels[:, :, [2, 1, 0]] if self.format.startswith("bgra") else pixels[:, :, :3]
        return np.ascontiguousarray(rgb)

    def run(self, frames: int | None = None, screenshot: str | None = None, keys: list[str] = ()) -> int:
        state = {"frame": 0}
        pending = list(keys)
        # rendercanvas only logs a failing draw and shows the previous frame: a scripted run must
        # notice, or a broken shader would pass as a green test.
        errors = _ErrorLogCounter()
        for name in ("wgpu", "rendercanvas"):
            logging.getLogger(name).addHandler(errors)

        def frame():
            if pending:
                self.press(pending.pop(0))
            texture = self.draw()
            state["frame"] += 1
            if frames is not None and state["frame"] >= frames:
                if screenshot:
                    save_rgb_png(Path(screenshot), self.read_frame(texture))
                    print(screenshot)
                self.canvas.close()

        self.canvas.request_draw(frame)
        try:
            self.loop.run()
        finally:
            for name in ("wgpu", "rendercanvas"):
                logging.getLogger(name).removeHandler(errors)
        if frames is not None and errors.count:
            print(f"wgpuviewer: error: {errors.count} error(s) logged while drawing", file=sys.stderr)
            return 1
        return 0


class _ErrorLogCounter(logging.Handler):
    def __init__(self):
        super().__init__(level=logging.ERROR)
        self.count = 0

    def emit(self, record):
        self.count += 1


def run_viewer(scene: Scene, technique: str, *, backend=None, frames=None, screenshot=None, keys=()) -> int:
    if frames is not None and frames < 1:
        raise UserError(f"--frames {frames}: expected a positive number of frames")
    if screenshot and frames is None:
        frames = max(len(keys), 0) + 3  # a screenshot implies a scripted run
    if screenshot and not screenshot.lower().endswith(".png"):
        raise UserError(f"--screenshot {screenshot}: expected a .png path")
    viewer = Viewer(scene, technique, backend)
    print(
        "keys: 1-9 technique, Left/Right cycle, WASD/QE move, drag to look, R reset camera, "
        "Shift+D cost view, Esc quit",
        file=sys.stderr,
    )
    return viewer.run(frames, screenshot, keys)
