"""The interactive viewer on any wgpu backend, in a rendercanvas window (``window``: glfw by default, Qt on request).

Compare relief-mapping techniques live: number keys and Left/Right switch techniques, F the texture filter
(Shift+F its derivative source), B splits the screen between two techniques or filters (both halves start alike,
Tab picks the half the keys change; drag the divider),
Shift+D shows the cost (depth fetches per pixel) and Shift+E the UV error against a high-layer-count POM
reference, both as heat maps with a legend that gives each half's mean and 95th percentile.
A HUD (imgui) shows FPS/frame/GPU time, the technique's description and live parameters, and the
keys (F1). Edited WGSL files are recompiled on the fly. Settings persist between sessions
(``settings``). ``keys.CONTROLS`` lists every key.

The viewer's parts: ``state`` (what each A/B half shows, the pure key transitions), ``window`` (the toolkit and
its platform hooks), ``input`` (events), ``builds`` (maps built in the background), ``frames`` (the frame encoder),
``runner`` (every run, interactive or scripted: ``--frames``, ``--keys``, ``--screenshot``).

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
from wgpuviewer.core import gpu as core_gpu
from wgpuviewer.core.commands import terminal_progress
from wgpuviewer.core.errors import InputError, UserError
from wgpuviewer.relief.filters import DEFAULT_DERIVATIVES, DEFAULT_FILTER, FILTERS, get_filter
from wgpuviewer.relief.output import save_rgb_png
from wgpuviewer.relief.renderer import DrawConfig, Renderer
from wgpuviewer.scene import Scene
from wgpuviewer.techniques import get_technique

from . import runner
from .builds import Builds
from .cameras import FlyCamera, OrbitCamera
from .frames import FrameEncoder
from .input import Input
from .keys import PRESSED, TECHNIQUE_KEYS
from .render_scale import AutoScale, Upscaler, next_choice, scaled_size
from .settings import LIMITS, Settings, save_session
from .state import Half, ViewerState
from .stats import FrameStats, GpuTimer, Summary, half_summaries, split_column
from .window import Window, prepare_gpu, toolkit

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
        shadows: str | None = None,
    ):
        toolkit(gui)  # a missing toolkit fails before any map is built
        self.settings = settings or Settings()
        s = self.settings
        self.scene = scene
        prepare_gpu(gui)  # before the first adapter request: the window's surface must work with its adapter
        self.gpu = core_gpu.get_gpu(backend)  # looked up at the call: tests stand in for it
        self.renderer = Renderer(scene, self.gpu)
        # What the first technique needs is built before the window opens (a bad file: one line, exit 2).
        with terminal_progress(f"maps for {technique}") as progress:
            self.renderer.prepare(technique, progress)
        #: Later techniques build on a worker thread while the window draws on (scripted runs: in the frame).
        self.builds = Builds(self.renderer, (not scripted) if background is None else background, show=self._show,
                             problem=self.problem, shown=lambda side: self.state.halves[side].technique)
        self.problems: list[str] = []  # shown in red in the HUD: a technique that could not be built, ...
        self.problem_time = 0.0
        #: Live parameters per technique (the HUD edits them) and relief-depth overrides per technique.
        self.params = {name: dict(values) for name, values in scene.technique_params.items()}
        self.height_scales: dict[str, float] = {}
        self.state = ViewerState.start(scene.techniques, technique, filter, derivatives)
        self.state.shadows = shadows
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
        self.frame_size = (0, 0)
        self.scripted = scripted
        #: The render scale (U): 'auto' or a fixed scale; auto chooses on a software adapter in interactive runs.
        self.render_choice = s.render_scale
        self.auto_scale = AutoScale() if self.gpu.software and not scripted else None
        self.upscaler: Upscaler | None = None  # built when a scale below 1 is first drawn
        self.window = Window(gui, self.gpu, size or (s.width, s.height), scripted=scripted, vsync=self.vsync)
        self.window.on_closing(self.builds.cancel)  # a map build stops as soon as the window closes
        self._last_time = time.perf_counter()
        self.stats = FrameStats()
        self.timer = GpuTimer(self.gpu.device) if GpuTimer.available(self.gpu) else None
        from .shader_reload import ShaderReloader

        self.reloader = ShaderReloader(self.renderer)
        self._shown_errors: list[str] = []
        self.frames = FrameEncoder(self.renderer, self.window.format, self.timer)
        #: The cost or error view's mean and p95 per half shown (the legend's numbers); what they were measured on.
        self.heat_summaries: list[Summary | None] = []
        self._summarised_errors = None  # the error map summarised
        self._cost_key, self._cost_time = None, -1e9  # what the fetches were measured on, and when
        self._want_screenshot = False
        from . import hud as hud_module

        self.hud = hud_module.Hud(self) if hud and hud_module.AVAILABLE else None
        if hud and self.hud is None:
            self.message("no HUD: install imgui-bundle (pip install 'wgpuviewer[window]')")
        self.input = Input(self)
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
        self.frames.invalidate_error_view()
        self.heat_summaries, self._summarised_errors, self._cost_key = [], None, None
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
        self.builds.request(side or self.state.side, name)
        self._update_title()

    def _show(self, side: str, name: str):
        self.state.show(side, name)
        self._update_title()

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

    def _save_screenshot(self, texture) -> None:
        try:
            self.screenshot(texture)
        except UserError as error:  # e.g. a read-only working folder: say so, keep drawing
            self.problem(str(error))

    def screenshot(self, texture) -> Path:
        stamp = time.strftime("%Y%m%d-%H%M%S")
        technique = self.state.halves["A"].technique
        name = f"wgpuviewer-{Path(self.scene.path).stem if self.scene.path else 'scene'}-{technique}-{stamp}.png"
        path = Path.cwd() / name
        save_rgb_png(path, self.read_frame(texture))
        self.message(f"screenshot: {path}")
        return path

    def technique_params(self, name: str) -> dict:
        """The live parameters of technique ``name`` (the dict the HUD edits)."""
        return self.params.setdefault(name, get_technique(name).defaults())

    def draw_config(self, half: Half) -> DrawConfig:
        """What a pass of ``half`` draws: its technique's live parameters and height-scale override, its filter with
        its live parameters and its derivative source, and the self-shadowing (L) and depth-offset (Z) overrides."""
        name = half.technique
        return DrawConfig.of(name, self.technique_params(name), self.height_scales.get(name), filter=half.filter,
                             filter_params=self.filter_params[half.filter], derivatives=half.derivatives,
                             shadows=self.state.shadows, depth_offset=self.state.depth_offset)

    def cost_scale(self, side: str = "A") -> float:
        """The fetch count the cost view paints as full heat on half ``side``."""
        name = self.state.halves[side].technique
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

    def cycle_shadows(self, key: str):
        self.state.cycle_shadows()
        self.message(f"shadows: {self.state.shadows_label}")

    def cycle_depth_offset(self, key: str):
        self.state.cycle_depth_offset()
        self.message(f"depth offset: {self.state.depth_offset_label}")

    def cycle_derivatives(self, key: str):
        half = self.state.cycle_derivatives()
        if not get_filter(half.filter).uses_derivatives:
            self.message(f"{half.filter} reads level 0: the derivative source does not change it")

    def cycle_technique(self, key: str):
        self.set_technique(self.state.next_technique(1 if key == "ArrowRight" else -1))

    def reset_stats(self, key: str):
        self.stats.reset()

    def reset_camera(self, key: str):
        self.cam.reset()

    def toggle_cost(self, key: str):
        self.toggle_mode("cost")

    def toggle_error(self, key: str):
        self.toggle_mode("error")

    def cycle_mode(self, key: str):
        self.set_mode(MODES[(MODES.index(self.mode) + 1) % len(MODES)])

    def toggle_split(self, key: str):
        self.state.toggle_split()  # B shows only techniques that were shown (built) before: nothing to build here

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

    def cycle_render_scale(self, key: str):
        self.render_choice = next_choice(self.render_choice)
        self.message(f"render scale: {self.render_scale_label}")

    @property
    def render_scale(self) -> float:
        """The fraction of the window's size the scene is drawn at (the HUD is always drawn at full size)."""
        if self.render_choice != "auto":
            return float(self.render_choice)
        return self.auto_scale.scale if self.auto_scale else 1.0

    @property
    def render_scale_label(self) -> str:
        """E.g. '0.5 (auto: 6.1 fps at 1)', '1 (auto)' or '0.75'."""
        auto = self.auto_scale
        if self.render_choice != "auto":
            return self.render_choice
        measured = f": {auto.fps:.1f} fps at {auto.measured_at:g}" if auto and auto.fps else ""
        return f"{self.render_scale:g} (auto{measured})"

    def quit(self, key: str):
        self.window.close()

    def stop_builds(self):
        """The window has closed: the map build under way stops (the run loop calls this once it ends)."""
        self.builds.stop()

    def _update_title(self):
        what = " | ".join(f"{h.technique} {h.filter} ({h.derivatives})" for _, h in self.state.shown())
        scale = f", render scale {self.render_scale:g}" if self.render_scale != 1.0 else ""
        self.window.set_title(f"wgpuviewer - {self.scene.name} - {what} ({self.mode}{scale})")

    # --- frames ------------------------------------------------------------------------------

    def draw(self):
        self.builds.poll()
        now = time.perf_counter()
        seconds, self._last_time = now - self._last_time, now
        dt = min(seconds, 0.1)
        self.stats.tick(now)
        if self.render_choice == "auto" and self.auto_scale and self.builds.current is None \
                and self.auto_scale.add(seconds):
            self.message(f"render scale: {self.render_scale_label}")
            self._update_title()
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
        self.input.fly(dt)
        window_texture = self.window.current_texture()
        if min(window_texture.size[:2]) < 1:
            raise wgpu.DrawCancelled("zero-sized frame")
        self.frame_size = window_texture.size[:2]
        scaled = self.render_scale != 1.0
        if scaled and self.upscaler is None:
            self.upscaler = Upscaler(self.gpu.device, self.window.format)
        # Below scale 1 the scene (and a screenshot of it) is drawn into a smaller texture, stretched over the window.
        texture = self.upscaler.frame(scaled_size(self.frame_size, self.render_scale)) if scaled else window_texture
        w, h = texture.size[:2]
        camera = self.cam.camera()
        state = self.state
        draws = [self.draw_config(half) for _, half in state.shown()]
        split_x = state.split_x if state.split else None
        if self.mode == "error":
            self.frames.update_error_view(draws, split_x, (w, h), camera, now)
        if self.mode in ("cost", "error"):
            self._update_heat_summaries(draws, split_x, (w, h), camera, now)
        screenshot = None
        if self._want_screenshot:
            self._want_screenshot = False
            screenshot = self._save_screenshot
        self.frames.encode(texture, draws, split_x, camera, self.mode, error_range=self.error_range,
                           screenshot=screenshot, hud=None if scaled else self.hud)
        if scaled:
            encoder = self.gpu.device.create_command_encoder(label="window:upscale")
            self.upscaler.encode(encoder, window_texture)
            if self.hud is not None:
                self.hud.encode(encoder, window_texture.create_view())
            self.gpu.device.queue.submit([encoder.finish()])
        return window_texture

    def _update_heat_summaries(self, draws: list[DrawConfig], split_x: float | None, size: tuple[int, int], camera,
                               now: float) -> None:
        """The legend's mean and p95 per half: of the error map the error view paints, or of the fetches of an
        offscreen render at the error view's resolution (again when what it shows changed, at most ~3 times a
        second)."""
        from . import error_view

        if self.mode == "error":
            values = self.frames.error_values
            if values is not None and values is not self._summarised_errors:
                self.heat_summaries, self._summarised_errors = half_summaries(values, split_x), values
            return
        size = error_view.map_size(size)
        key = (size, tuple(draws), split_x is not None and round(split_x, 3), camera)
        if key == self._cost_key or (self._cost_key is not None and now - self._cost_time < 0.3):
            return
        values = error_view.cost_map(self.renderer, draws[0], size, camera)
        if split_x is not None:
            xs = split_column(split_x, size[0])
            values[:, xs:] = error_view.cost_map(self.renderer, draws[1], size, camera)[:, xs:]
        self.heat_summaries, self._cost_key, self._cost_time = half_summaries(values, split_x), key, now

    def read_frame(self, texture) -> np.ndarray:
        return self.frames.read(texture)

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
            show_hud=self.show_hud, show_stats=self.show_stats, render_scale=self.render_choice,
            last_scene=str(self.scene.path) if self.scene.path else "", last_technique=self.state.halves["A"].technique,
        )


def run_viewer(
    scene: Scene, technique: str, *, backend=None, frames=None, screenshot=None, keys=(),
    gui: str = "glfw", settings: Settings | None = None, size=None, save: bool | None = None,
    filter: str = DEFAULT_FILTER, derivatives: str = DEFAULT_DERIVATIVES, shadows: str | None = None,
) -> int:
    """Open the window. Interactive runs save the settings on exit (``save``); scripted ones don't."""
    frames = runner.scripted_frames(frames, screenshot, keys)
    scripted = frames is not None
    viewer = Viewer(scene, technique, backend, gui=gui, settings=settings, size=size, scripted=scripted,
                    filter=filter, derivatives=derivatives, shadows=shadows)
    if not scripted:
        print("keys: F1 help, 1-9 technique, F filter, B A/B split, Shift+D cost, Shift+E error, H hide UI, Esc quit",
              file=sys.stderr)
    saves = save if save is not None else not scripted
    code = runner.run(viewer, frames, screenshot, keys,
                      on_end=(lambda: save_session(viewer.current_settings())) if saves else None)
    if code == 0 and scripted and viewer.problems:  # a scripted run reports what the HUD showed
        print(f"wgpuviewer: error: {viewer.problems[0]}", file=sys.stderr)
        return 2
    return code
