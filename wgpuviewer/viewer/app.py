"""The interactive viewer on any wgpu backend, in a rendercanvas window (``window``: glfw by default, Qt on request).

Compare relief-mapping techniques live: number keys and Left/Right switch techniques, F the texture filter
(Shift+F its derivative source), B splits the screen between two techniques or filters (drag the divider),
Shift+D shows the cost (depth fetches per pixel) and Shift+E the UV error against a high-layer-count POM
reference, both as heat maps with a legend.
A HUD (imgui) shows FPS/frame/GPU time, the technique's description and live parameters, and the
keys (F1). Edited WGSL files are recompiled on the fly. Settings persist between sessions
(``settings``). ``keys.CONTROLS`` lists every key.

Runs, interactive or scripted (``--frames``, ``--keys``, ``--screenshot``), go through ``runner``.

The viewer owns what the user tunes live: the parameters of each technique (``params``, starting from the scene's),
a relief-depth override per technique (``height_scales``), each filter's parameters (``filter_params``) and what each
A/B half shows (``state``, a ``ViewerState``); each pass gets them as a frozen ``DrawConfig`` (``draw_config``).
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import wgpu

from wgpuviewer.camera import normalize
from wgpuviewer.core.cli import terminal_progress
from wgpuviewer.core.errors import InputError, UserError
from wgpuviewer.core.gpu import get_gpu
from wgpuviewer.relief.filters import DEFAULT_DERIVATIVES, DEFAULT_FILTER, FILTERS, get_filter
from wgpuviewer.relief.output import save_rgb_png
from wgpuviewer.relief.renderer import DEPTH_FORMAT, DrawConfig, Renderer
from wgpuviewer.relief.techniques import get_technique
from wgpuviewer.scene import Camera, Scene

from . import runner
from .builds import MapBuild
from .cameras import FlyCamera, OrbitCamera
from .keys import FLY_KEYS, PRESSED, TECHNIQUE_KEYS
from .settings import CONFIG_ENV, LIMITS, Settings, save_settings, settings_path
from .state import Half, ViewerState
from .stats import FrameStats, GpuTimer
from .window import Window, toolkit

MODES = ("color", "cost", "error")


class Viewer:
    def __init__(
        self,
        scene: Scene,
        technique: str,
        backend: str | None,
        *,
        gui: str = "glfw",
        settings: Settings | None = None,
        size: tuple[int, int] | None = None,
        hud: bool = True,
        scripted: bool = False,
        background: bool | None = None,
        filter: str = DEFAULT_FILTER,
        derivatives: str = DEFAULT_DERIVATIVES,
    ):
        toolkit(gui)  # a missing toolkit fails before any map is built
        self.settings = settings or Settings()
        s = self.settings
        self.scene = scene
        self.gpu = get_gpu(backend)
        self.renderer = Renderer(scene, self.gpu)
        # What the first technique needs is built before the window opens (a bad file: one line, exit 2).
        with terminal_progress(f"maps for {technique}") as progress:
            self.renderer.prepare(technique, progress)
        #: Later techniques build on a worker thread while the window draws on (scripted runs: in the frame).
        self.background = (not scripted) if background is None else background
        self.build: MapBuild | None = None
        self.wanted: dict[str, str] = {}  # side -> the technique last asked for there (while building)
        self.problems: list[str] = []  # shown in red in the HUD: a technique that could not be built, ...
        self.problem_time = 0.0
        #: Live parameters per technique (the HUD edits them) and relief-depth overrides per technique.
        self.params = {name: dict(values) for name, values in scene.technique_params.items()}
        self.height_scales: dict[str, float] = {}
        self.state = ViewerState.start(scene.techniques, technique, filter, derivatives)
        self.filter_params = {name: f.defaults() for name, f in FILTERS.items()}  # live, per filter
        self.mode = "color"
        self.camera_mode = s.camera_mode
        self.fly = FlyCamera(scene.camera, s.look_sensitivity)
        self.orbit = OrbitCamera(scene.camera, s.look_sensitivity, s.zoom_sensitivity)
        self.move_speed = s.move_speed
        self.show_hud, self.show_stats, self.show_help = s.show_hud, s.show_stats, False
        self.vsync = s.vsync and not scripted  # scripted runs draw as fast as they can
        self.fullscreen = False
        self.messages: list[str] = []
        self.error_range = 2.0
        self.error_texels = (1, 1)
        self.held: set[str] = set()
        self.drag_from: tuple[float, float] | None = None
        self.dragging_divider = False
        self.frame_size = (0, 0)
        self.scripted = scripted
        self.window = Window(gui, self.gpu, size or (s.width, s.height), scripted=scripted, vsync=self.vsync)
        self.format = self.window.format
        self._depth = None
        self._last_time = time.perf_counter()
        self.stats = FrameStats()
        self.timer = GpuTimer(self.gpu.device) if GpuTimer.available(self.gpu) else None
        from .shader_reload import ShaderReloader

        self.reloader = ShaderReloader(self.renderer)
        self._shown_errors: list[str] = []
        self._error = None  # ErrorOverlay, built on first use
        self._error_key = None
        self._error_time = -1e9
        from . import hud as hud_module

        self.hud = hud_module.Hud(self) if hud and hud_module.AVAILABLE else None
        if hud and self.hud is None:
            self.message("no HUD: install imgui-bundle (pip install 'wgpuviewer[window]')")
        self.window.on(self.on_key_down, "key_down")
        self.window.on(self.on_key_up, "key_up")
        self.window.on(self.on_pointer, "pointer_down", "pointer_up", "pointer_move")
        self.window.on(self.on_wheel, "wheel")
        if s.fullscreen:
            self.set_fullscreen(True)
        self._update_title()

    # --- state changes (keys and HUD) ----------------------------------------------------------

    def message(self, text: str):
        self.messages.append(text)
        print(text, file=sys.stderr)

    @property
    def cam(self):
        return self.orbit if self.camera_mode == "orbit" else self.fly

    @property
    def look_sensitivity(self) -> float:
        return self.fly.sensitivity

    @look_sensitivity.setter
    def look_sensitivity(self, value: float):
        self.fly.sensitivity = self.orbit.sensitivity = float(value)

    def set_mode(self, mode: str):
        if mode == "error":  # the error view compares against its reference technique: build what it needs
            from .error_view import REFERENCE

            try:
                self.renderer.prepare(REFERENCE)
            except (UserError, InputError) as error:
                self.problem(f"error view: {error}")
                return
        self.mode = mode
        self._error_key = None
        self._update_title()

    def toggle_mode(self, mode: str):
        self.set_mode("color" if self.mode == mode else mode)

    def set_camera_mode(self, mode: str):
        if mode == self.camera_mode:
            return
        # Keep the view: the new camera starts where the old one looks from.
        current = self.cam.camera()
        if mode == "orbit":
            self.orbit.start = replace(self.scene.camera, position=current.position,
                                       target=self.orbit.target if np.isfinite(self.orbit.target).all()
                                       else self.scene.camera.target)
            self.orbit.reset()
            self.orbit.start = self.scene.camera
        else:
            self.fly.position = np.asarray(current.position, np.float64)
            f = normalize(np.subtract(current.target, current.position))
            self.fly.yaw = float(np.arctan2(f[0], -f[2]))
            self.fly.pitch = float(np.arcsin(np.clip(f[1], -1.0, 1.0)))
        self.camera_mode = mode

    def set_technique(self, name: str, side: str | None = None):
        """Show ``name`` on the active half (or ``side``) once what it needs is built; until then the half keeps
        its technique. A problem (a bad texture file) is shown in the HUD and the technique stays."""
        side = side or self.state.side
        self.wanted[side] = name
        if self.ready(name):
            self._show(side, name)
        elif not self.background:
            try:
                self.renderer.prepare(name)
            except (UserError, InputError) as error:
                self.problem(str(error))
                return
            self._show(side, name)
        elif self.build is None:
            self.build = MapBuild(self.renderer, name, side)
        self._update_title()

    def ready(self, name: str) -> bool:
        return not self.renderer.missing(name)

    def _show(self, side: str, name: str):
        self.state.show(side, name)
        self._update_title()

    def _poll_build(self):
        """A finished build: show its technique where it is still wanted, or report its problem; then build
        what was asked for meanwhile."""
        build = self.build
        if build is None or not build.finished:
            return
        self.build = None
        if build.error:
            self.problem(build.error)
            if self.wanted.get(build.side) == build.technique:  # not asked for again until a key asks
                self.wanted[build.side] = self.state.halves[build.side].technique
        elif self.wanted.get(build.side) == build.technique:
            self._show(build.side, build.technique)
        for side, name in self.wanted.items():
            if self.build is None and not self.ready(name):
                self.build = MapBuild(self.renderer, name, side)

    def problem(self, text: str):
        """A problem the viewer survives (shown in red in the HUD for a while, and on stderr)."""
        self.problems.append(text)
        self.problem_time = time.perf_counter()
        print(f"wgpuviewer: error: {text}", file=sys.stderr)

    def current_problem(self, seconds: float = 20.0) -> str | None:
        """The last problem, while it is recent enough to show."""
        if self.problems and time.perf_counter() - self.problem_time < seconds:
            return self.problems[-1]
        return None

    def set_vsync(self, on: bool):
        self.vsync = bool(on)
        problem = self.window.set_vsync(self.vsync)
        if problem:
            self.message(f"vsync: {problem}")
        self.message(f"vsync {'on' if self.vsync else 'off'}")

    def set_fullscreen(self, on: bool):
        problem = self.window.set_fullscreen(on)
        if problem:
            self.message(f"fullscreen: {problem}")
        else:
            self.fullscreen = on

    def screenshot(self, texture) -> Path:
        stamp = time.strftime("%Y%m%d-%H%M%S")
        technique = self.state.halves["A"].technique
        name = f"wgpuviewer-{Path(self.scene.path).stem if self.scene.path else 'scene'}-{technique}-{stamp}.png"
        path = Path.cwd() / name
        save_rgb_png(path, self.read_frame(texture))
        self.message(f"screenshot: {path}")
        return path

    def reset_stats(self):
        self.stats.reset()

    def technique_params(self, name: str) -> dict:
        """The live parameters of technique ``name`` (the dict the HUD edits)."""
        return self.params.setdefault(name, get_technique(name).defaults())

    def draw_config(self, half: Half) -> DrawConfig:
        """What a pass of ``half`` draws: its technique's live parameters and height-scale override, its filter with
        its live parameters and its derivative source."""
        name = half.technique
        return DrawConfig.of(name, self.technique_params(name), self.height_scales.get(name), filter=half.filter,
                             filter_params=self.filter_params[half.filter], derivatives=half.derivatives)

    def cost_scale(self) -> float:
        name = self.state.halves["A"].technique
        return get_technique(name).cost_scale(self.technique_params(name))

    def material_height_scales(self) -> str:
        return ", ".join(f"{m.height_scale:g}" for m in self.scene.materials.values())

    def material_height_scale(self) -> float:
        return float(next(iter(self.scene.materials.values())).height_scale)

    @property
    def error_reference(self) -> str:
        from .error_view import REFERENCE, REFERENCE_LAYERS

        return f"{REFERENCE} {REFERENCE_LAYERS} layers"

    # --- input -------------------------------------------------------------------------------

    def press(self, key: str):
        """What a key does (keys.CONTROLS; also used by scripted runs)."""
        control = PRESSED.get(key)
        if control is not None:
            getattr(self, control.action)(key)
        self._update_title()

    # --- the actions of keys.CONTROLS (each takes the key pressed) -----------------------------------------

    def pick_technique(self, key: str):
        name = self.state.technique_for_key(key)
        if name is None:
            self.message(f"{key}: {TECHNIQUE_KEYS[key]} is not in this scene's techniques")
        else:
            self.set_technique(name)

    def cycle_filter(self, key: str):
        self.state.cycle_filter()

    def cycle_derivatives(self, key: str):
        half = self.state.cycle_derivatives()
        if not get_filter(half.filter).uses_derivatives:
            self.message(f"{half.filter} reads level 0: the derivative source does not change it")

    def cycle_technique(self, key: str):
        self.set_technique(self.state.next_technique(1 if key == "ArrowRight" else -1))

    def reset_camera(self, key: str):
        self.cam.reset()

    def toggle_cost(self, key: str):
        self.toggle_mode("cost")

    def toggle_error(self, key: str):
        self.toggle_mode("error")

    def cycle_mode(self, key: str):
        self.set_mode(MODES[(MODES.index(self.mode) + 1) % len(MODES)])

    def toggle_split(self, key: str):
        state = self.state
        state.toggle_split()
        b = state.halves["B"]
        if state.split and not self.ready(b.technique):  # B draws A's technique until its maps are built
            wanted = b.technique
            state.show("B", state.halves["A"].technique)
            self.set_technique(wanted, "B")

    def switch_half(self, key: str):
        self.state.switch_half()

    def toggle_camera(self, key: str):
        self.set_camera_mode("fly" if self.camera_mode == "orbit" else "orbit")

    def toggle_hud(self, key: str):
        self.show_hud = not self.show_hud

    def toggle_stats(self, key: str):
        self.show_stats = not self.show_stats

    def toggle_help(self, key: str):
        self.show_help = not self.show_help

    def request_screenshot(self, key: str):
        self._want_screenshot = True

    def toggle_vsync(self, key: str):
        self.set_vsync(not self.vsync)

    def toggle_fullscreen(self, key: str):
        self.set_fullscreen(not self.fullscreen)

    def reload_shaders(self, key: str):
        self.reloader.reload()

    def quit(self, key: str):
        self.window.close()

    def on_key_down(self, event):
        key = event["key"]
        if key in FLY_KEYS:
            self.held.add(key)
        else:
            self.press(key)

    def on_key_up(self, event):
        self.held.discard(event["key"].lower())  # Shift released first: "D" ends the held "d"

    def _divider_hit(self, x: float) -> bool:
        width = self.window.logical_size()[0]
        return self.state.split and abs(x - self.state.split_x * width) <= 8

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
                width = max(self.window.logical_size()[0], 1)
                self.state.split_x = float(np.clip(event["x"] / width, 0.02, 0.98))
            elif self.drag_from is not None:
                self.cam.look(event["x"] - self.drag_from[0], event["y"] - self.drag_from[1])
                self.drag_from = (event["x"], event["y"])

    def on_wheel(self, event):
        steps = event["dy"] / 100.0
        if self.camera_mode == "orbit":
            self.orbit.zoom(steps)
        else:
            lo, hi = LIMITS["move_speed"]
            self.move_speed = float(np.clip(self.move_speed * 1.1 ** (-steps), lo, hi))

    def _update_title(self):
        what = " | ".join(f"{h.technique} {h.filter} ({h.derivatives})" for _, h in self.state.shown())
        self.window.set_title(f"wgpuviewer - {self.scene.name} - {what} ({self.mode})")

    # --- frames ------------------------------------------------------------------------------

    def _scene_passes(self, w: int, h: int, camera: Camera) -> list:
        """(DrawConfig, scissor) of the passes that draw the scene: one, or the two halves of A/B."""
        state = self.state
        if not state.split:
            return [(self.draw_config(state.halves["A"]), None)]
        xs = int(np.clip(round(state.split_x * w), 1, w - 1)) if w > 1 else 1
        return [(self.draw_config(state.halves["A"]), (0, 0, xs, h)),
                (self.draw_config(state.halves["B"]), (xs, 0, w - xs, h))]

    def _update_error_view(self, w: int, h: int, camera: Camera, now: float):
        """Recompute the error map when what it shows changed (at most ~3 times a second)."""
        from . import error_view

        size = error_view.map_size((w, h))
        state = self.state
        draws = [self.draw_config(half) for _, half in state.shown()]
        key = (size, tuple(draws), state.split and round(state.split_x, 3), camera)
        if key == self._error_key or (self._error_key is not None and now - self._error_time < 0.3):
            return
        if self._error is None:
            self._error = error_view.ErrorOverlay(self.gpu.device, self.format)
        # One reference per height-scale override in use (each technique is compared on its own relief).
        references = {}
        for draw in draws:
            if draw.height_scale not in references:
                references[draw.height_scale] = error_view.reference_render(self.renderer, size, camera,
                                                                            draw.height_scale)

        def error_of(draw):
            return error_view.error_map(self.renderer, draw, size, camera, references[draw.height_scale])

        values = error_of(draws[0])
        if state.split:
            right = error_of(draws[1])
            xs = int(round(state.split_x * size[0]))
            values[:, xs:] = right[:, xs:]
        self.error_texels = error_view.texel_size(self.renderer)
        self._error.upload(values)
        self._error_key, self._error_time = key, now

    def draw(self):
        self._poll_build()
        now = time.perf_counter()
        dt, self._last_time = min(now - self._last_time, 0.1), now
        self.stats.tick(now)
        if self.timer:
            for ms in self.timer.collect():
                self.stats.add_gpu_time(ms)
        self.reloader.poll(now)
        if self.reloader.errors != self._shown_errors:  # new compile errors (or fixed ones): say so once
            self._shown_errors = list(self.reloader.errors)
            for error in self._shown_errors:
                print(f"shader error: {error}", file=sys.stderr)
            if not self._shown_errors:
                self.message("shaders reloaded")
        if self.held and self.camera_mode == "fly":
            step = np.sum([FLY_KEYS[k] for k in self.held], axis=0) * self.move_speed * dt
            self.fly.move(*step)
        texture = self.window.current_texture()
        w, h = texture.size[:2]
        if w < 1 or h < 1:
            raise wgpu.DrawCancelled("zero-sized frame")
        self.frame_size = (w, h)
        device = self.gpu.device
        if self._depth is None or self._depth.size[:2] != (w, h):
            self._depth = device.create_texture(
                label="window:depth", size=(w, h, 1), format=DEPTH_FORMAT, usage="RENDER_ATTACHMENT"
            )
        camera = self.cam.camera()
        if self.mode == "error":
            self._update_error_view(w, h, camera, now)
        view = texture.create_view()
        scene_mode = "cost" if self.mode == "cost" else "color"
        passes = self._scene_passes(w, h, camera)
        if self.timer:
            self.timer.begin_frame()
        # One submit per scene pass: each pass writes the renderer's frame/params uniforms first.
        for i, (draw, scissor) in enumerate(passes):
            encoder = device.create_command_encoder(label="window")
            writes = self.timer.writes(i == 0, i == len(passes) - 1) if self.timer else None
            self.renderer.encode(
                encoder, [view], self._depth.create_view(), (self.format,), draw, camera, (w, h),
                scene_mode, clear=(i == 0), scissor=scissor, timestamp_writes=writes,
            )
            if self.timer and i == len(passes) - 1:
                self.timer.encode_resolve(encoder)
            device.queue.submit([encoder.finish()])
        if self.timer:
            self.timer.after_submit()
        encoder = device.create_command_encoder(label="window:overlay")
        if self.mode == "error" and self._error is not None:
            self._error.encode(encoder, view, (0, 0, w, h), self.error_range)
        if getattr(self, "_want_screenshot", False):  # the scene without the HUD
            self._want_screenshot = False
            device.queue.submit([encoder.finish()])
            try:
                self.screenshot(texture)
            except UserError as error:  # e.g. a read-only working folder: say so, keep drawing
                self.problem(str(error))
            encoder = device.create_command_encoder(label="window:hud")
        if self.hud is not None:
            self.hud.encode(encoder, view)
        device.queue.submit([encoder.finish()])
        return texture

    def read_frame(self, texture) -> np.ndarray:
        w, h = texture.size[:2]
        raw = self.gpu.device.queue.read_texture(  # wgpu-py pads the rows to 256 bytes itself
            {"texture": texture, "mip_level": 0, "origin": (0, 0, 0)},
            {"offset": 0, "bytes_per_row": w * 4, "rows_per_image": h},
            (w, h, 1),
        )
        pixels = np.frombuffer(raw, np.uint8).reshape(h, w, 4)
        rgb = pixels[:, :, [2, 1, 0]] if self.format.startswith("bgra") else pixels[:, :, :3]
        return np.ascontiguousarray(rgb)

    def current_settings(self) -> Settings:
        """What to persist: window size (when not fullscreen), camera and UI choices, scene, technique."""
        s = self.settings
        if not self.fullscreen:
            lw, lh = self.window.logical_size()
            if lw >= LIMITS["width"][0] and lh >= LIMITS["height"][0]:
                s = replace(s, width=int(round(lw)), height=int(round(lh)))
        lo, hi = LIMITS["look_sensitivity"]
        return replace(
            s, fullscreen=self.fullscreen, vsync=self.vsync, camera_mode=self.camera_mode,
            move_speed=float(np.clip(self.move_speed, *LIMITS["move_speed"])),
            look_sensitivity=float(np.clip(self.look_sensitivity, lo, hi)),
            show_hud=self.show_hud, show_stats=self.show_stats,
            last_scene=str(self.scene.path) if self.scene.path else "", last_technique=self.state.halves["A"].technique,
        )


def save_session(settings: Settings) -> None:
    """Save the settings at the end of a session; a folder that cannot be written is a warning naming it and
    the variable that moves it, never a failed session."""
    try:
        path = save_settings(settings)
        print(f"settings saved to {path}", file=sys.stderr)
    except (OSError, UserError) as error:
        reason = getattr(error, "strerror", None) or str(error)
        print(f"wgpuviewer: warning: settings not saved: {settings_path()} cannot be written ({reason}); "
              f"set {CONFIG_ENV} to a writable folder", file=sys.stderr)


def run_viewer(
    scene: Scene, technique: str, *, backend=None, frames=None, screenshot=None, keys=(),
    gui: str = "glfw", settings: Settings | None = None, size=None, save: bool | None = None,
    filter: str = DEFAULT_FILTER, derivatives: str = DEFAULT_DERIVATIVES,
) -> int:
    """Open the window. Interactive runs save the settings on exit (``save``); scripted ones don't."""
    frames = runner.scripted_frames(frames, screenshot, keys)
    scripted = frames is not None
    viewer = Viewer(scene, technique, backend, gui=gui, settings=settings, size=size, scripted=scripted,
                    filter=filter, derivatives=derivatives)
    if not scripted:
        print("keys: F1 help, 1-9 technique, F filter, B A/B split, Shift+D cost, Shift+E error, H hide UI, Esc quit",
              file=sys.stderr)
    code = runner.run(viewer, frames, screenshot, keys)
    if save if save is not None else not scripted:
        save_session(viewer.current_settings())
    if code == 0 and scripted and viewer.problems:  # a scripted run reports what the HUD showed
        print(f"wgpuviewer: error: {viewer.problems[0]}", file=sys.stderr)
        return 2
    return code
