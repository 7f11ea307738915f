"""The viewer's on-screen UI (Dear ImGui through ``wgpu.utils.imgui``, package ``imgui-bundle``).

Panels: statistics (X), info with the technique's description and live parameters and the texture filter (F,
Shift+F: its derivative source) with its parameters, help (F1),
a colour legend in the cost and error views, labels of the A/B halves, status and shader errors.
H hides everything. The HUD draws into the frame in its own render pass, after the scene.
"""

from __future__ import annotations

try:
    from imgui_bundle import imgui
    from wgpu.utils.imgui import ImguiRenderer
except ImportError:  # the viewer then runs without a HUD (window title only)
    imgui = None
    ImguiRenderer = None

import functools

import numpy as np

from wgpuviewer.core.color import heat, linear_to_srgb
from wgpuviewer.relief import autotable
from wgpuviewer.relief.filters import DERIVATIVE_SOURCES, FILTERS, get_filter
from wgpuviewer.relief.maps import height_scale_adjustable
from wgpuviewer.relief.techniques import get_technique

from .keys import CONTROLS

AVAILABLE = imgui is not None

WHITE = (1.0, 1.0, 1.0, 1.0)
YELLOW = (1.0, 0.85, 0.3, 1.0)
RED = (1.0, 0.35, 0.3, 1.0)
GREY = (0.7, 0.7, 0.7, 1.0)
MARGIN = 8.0
#: Below this window size (logical pixels) the HUD is compact.
COMPACT_SIZE = (640, 400)


@functools.lru_cache(maxsize=16)
def auto_lines(renderer, max_error: float) -> list[str]:
    """What auto chooses per view-angle range at ``max_error`` on each material of the renderer's scene (from its
    measured table; the layers view, --mode layers, paints the candidate numbers)."""
    lines = [f"auto at max_error {max_error:g}: budget {autotable.budgets()[autotable.budget_level(max_error)]:g} texel"]
    for name in renderer.scene.materials:
        lines.append(f"{name}:")
        lines += [f"  {line}" for line in autotable.describe(renderer.auto_table(name), max_error)]
    return lines


class Hud:
    def __init__(self, viewer):
        self.viewer = viewer
        self.imgui = ImguiRenderer(viewer.gpu.device, viewer.window.canvas)
        io = imgui.get_io()
        io.set_ini_filename("")  # window positions are not persisted next to the user's cwd
        self.drawn_panels: list[str] = []  # what the last frame showed (tests, debugging)
        self.rects: dict[str, tuple[float, float, float, float]] = {}  # panel -> (x, y, w, h) in the last frame

    def encode(self, encoder, view) -> None:
        """Build this frame's UI and record it into ``view``."""
        renderer = self.imgui
        imgui.set_current_context(renderer.imgui_context)
        window = self.viewer.window
        ratio = window.pixel_ratio()
        renderer.backend.io.display_framebuffer_scale = (ratio, ratio)
        renderer.backend.io.display_size = window.logical_size()
        imgui.new_frame()
        try:
            self.build()
        finally:
            imgui.render()
        rpass = encoder.begin_render_pass(
            label="hud", color_attachments=[{"view": view, "load_op": "load", "store_op": "store"}]
        )
        renderer.backend.render(imgui.get_draw_data(), rpass)
        rpass.end()

    # --- panels --------------------------------------------------------------------------------

    def _record(self, name: str) -> None:
        """Inside a panel: note it was drawn, and where (tests check the layout fits small windows)."""
        (x, y), (w, h) = imgui.get_window_pos(), imgui.get_window_size()
        self.rects[name] = (x, y, w, h)
        self.drawn_panels.append(name)

    def build(self) -> None:
        v = self.viewer
        self.drawn_panels = []
        self.rects = {}
        if not v.show_hud:
            return
        width, height = imgui.get_io().display_size
        #: Small windows (e.g. 320x240): short statistics, the technique panel collapsed beside them, no overlap.
        self.compact = width < COMPACT_SIZE[0] or height < COMPACT_SIZE[1]
        flags = imgui.WindowFlags_.always_auto_resize | imgui.WindowFlags_.no_focus_on_appearing
        if v.show_stats:
            self._stats_panel(flags, width)
        self._info_panel(flags, width)
        if v.show_help:
            self._help_panel(flags, width, height)
        if v.mode in ("cost", "error"):
            self._legend(width, height)
        if v.state.split:
            self._split_labels(width)
        self._status(flags, width, height)

    def _stats_panel(self, flags, width) -> None:
        v = self.viewer
        imgui.set_next_window_pos((MARGIN, MARGIN), imgui.Cond_.always if self.compact else imgui.Cond_.first_use_ever)
        if self.compact:
            imgui.set_next_window_size_constraints((0, 0), (width / 2 - 1.5 * MARGIN, 1e4))
        imgui.set_next_window_bg_alpha(0.6)
        imgui.begin("Statistics", None, flags | (imgui.WindowFlags_.no_title_bar if self.compact else 0))
        if self.compact:
            imgui.text(f"FPS {v.stats.fps or 0:.1f}")
            imgui.text(f"{v.stats.frame_ms or 0:.1f} ms" + (f", GPU {v.stats.gpu_time_ms:.2f}" if v.stats.gpu_ms else ""))
        else:
            for line in v.stats.lines():
                imgui.text(line)
            if not v.timer:
                imgui.text_colored(GREY, "GPU time: adapter has no timestamp queries")
            w, h = v.frame_size
            imgui.text_colored(GREY, f"{w}x{h} px, vsync {'on' if v.vsync else 'off'}")
            imgui.text_colored(GREY, v.gpu.summary.split(" (")[0] + " " + v.gpu.summary.rsplit(" via ", 1)[-1])
            imgui.text_colored(GREY, "C resets, X hides")
        self._record("stats")
        imgui.end()

    @staticmethod
    def _sliders(params, values: dict, tag: str) -> None:
        """One widget per registry parameter (checkbox, int or float slider within its range), editing ``values``."""
        for p in params:
            label = f"{p.name}##{tag}"
            current = values.get(p.name, p.default)
            if p.kind is bool:
                changed, new = imgui.checkbox(label, bool(current))
            elif p.kind is int:
                flags = imgui.SliderFlags_.logarithmic if p.max / max(p.min, 1) > 100 else 0
                changed, new = imgui.slider_int(label, int(current), int(p.min), int(p.max), "%d", flags)
            else:
                changed, new = imgui.slider_float(label, float(current), float(p.min), float(p.max))
            if changed:
                values[p.name] = p.kind(new)
            if imgui.is_item_hovered():
                imgui.set_tooltip(p.doc)

    def _params(self, technique_name: str, tag: str) -> None:
        v = self.viewer
        technique = get_technique(technique_name)
        self._sliders(technique.params, v.technique_params(technique_name), tag)
        if technique.needs_depth and height_scale_adjustable(technique.textures):
            overrides = v.height_scales
            changed, on = imgui.checkbox(f"override height scale##{tag}", technique_name in overrides)
            if changed:
                if on:
                    overrides[technique_name] = v.material_height_scale()
                else:
                    overrides.pop(technique_name, None)
            if technique_name in overrides:
                _, overrides[technique_name] = imgui.slider_float(
                    f"height scale##{tag}", float(overrides[technique_name]), 0.0, 0.5, "%.3f"
                )
            else:
                imgui.text_colored(GREY, f"height scale {v.material_height_scales()} (materials)")

    def _info_panel(self, flags, width) -> None:
        v = self.viewer
        if self.compact:  # beside the statistics, collapsed to its title (click to open)
            imgui.set_next_window_pos((width - MARGIN, MARGIN), imgui.Cond_.always, (1.0, 0.0))
            imgui.set_next_window_size((width / 2 - 1.5 * MARGIN, 0), imgui.Cond_.always)
            imgui.set_next_window_collapsed(True, imgui.Cond_.first_use_ever)
        else:
            imgui.set_next_window_pos((width - MARGIN, MARGIN), imgui.Cond_.first_use_ever, (1.0, 0.0))
            imgui.set_next_window_size((min(340, width / 2), 0), imgui.Cond_.first_use_ever)
        imgui.set_next_window_bg_alpha(0.6)
        state = v.state
        a = state.halves["A"].technique
        title = f"{state.key_for(a)} {a}" + (f" | {state.halves['B'].technique}" if state.split else "")
        if not imgui.begin(f"{title}###Technique", None, imgui.WindowFlags_.no_focus_on_appearing)[0]:
            self._record("info")  # collapsed: the title bar alone
            imgui.end()
            return
        imgui.push_item_width(-140)
        for tag, half in state.shown():
            name = half.technique
            t = get_technique(name)
            prefix = f"{tag}: " if state.split else ""
            active = state.split and tag == state.active_side
            imgui.text_colored(YELLOW if active else WHITE, f"{prefix}{state.key_for(t.name)}  {t.name}")
            imgui.push_text_wrap_pos(0.0)
            imgui.text_colored(GREY, t.description)
            imgui.pop_text_wrap_pos()
            self._params(name, tag)
            if t.name == "auto":
                for line in auto_lines(v.renderer, v.technique_params(name)["max_error"]):
                    imgui.text_colored(GREY, line)
            self._filter(half, tag)
            imgui.separator()
        modes = ("color", "cost", "error")
        for i, mode in enumerate(modes):
            if i:
                imgui.same_line()
            if imgui.radio_button(mode, v.mode == mode):
                v.set_mode(mode)
        if v.mode == "error":
            _, v.error_range = imgui.slider_float("error range (texels)", v.error_range, 0.1, 32.0, "%.1f",
                                                  imgui.SliderFlags_.logarithmic)
        changed, orbit = imgui.checkbox("orbit camera (O)", v.camera_mode == "orbit")
        if changed:
            v.set_camera_mode("orbit" if orbit else "fly")
        _, v.move_speed = imgui.slider_float("move speed", v.move_speed, 0.01, 100.0, "%.2f",
                                             imgui.SliderFlags_.logarithmic)
        _, v.look_sensitivity = imgui.slider_float("mouse sensitivity", v.look_sensitivity, 0.0001, 0.1, "%.4f",
                                                   imgui.SliderFlags_.logarithmic)
        changed, vsync = imgui.checkbox("vsync (V)", v.vsync)
        if changed:
            v.set_vsync(vsync)
        imgui.pop_item_width()
        self._record("info")
        imgui.end()

    def _filter(self, half, tag: str) -> None:
        """The half's texture filter (a combo, F cycles it), its derivative source (Shift+F) and parameters."""
        v = self.viewer
        names = list(FILTERS)
        changed, index = imgui.combo(f"filter (F)##{tag}", names.index(half.filter), names)
        if changed:
            half.filter = names[index]
        if imgui.is_item_hovered():
            imgui.set_tooltip(get_filter(half.filter).description)
        sources = list(DERIVATIVE_SOURCES)
        changed, index = imgui.combo(f"derivatives (Shift+F)##{tag}", sources.index(half.derivatives), sources)
        if changed:
            half.derivatives = sources[index]
        if imgui.is_item_hovered():
            imgui.set_tooltip(DERIVATIVE_SOURCES[half.derivatives].description)
        f = get_filter(half.filter)
        self._sliders(f.params, v.filter_params[f.name], f"{tag}:{f.name}")

    def _help_panel(self, flags, width, height) -> None:
        imgui.set_next_window_pos((width / 2, height / 2), imgui.Cond_.appearing, (0.5, 0.5))
        imgui.set_next_window_bg_alpha(0.85)
        imgui.begin("Keys (F1 closes)", None, flags)
        for control in CONTROLS:
            imgui.text_colored(YELLOW, f"{control.label:<14}")
            imgui.same_line(130)
            imgui.text(control.help)
        self._record("help")
        imgui.end()

    def _legend(self, width, height) -> None:
        v = self.viewer
        draw = imgui.get_foreground_draw_list()
        x0, bar_w, bar_h = 20.0, min(320.0, width - 40.0), 14.0
        y0 = height - (80.0 if v.state.split else 50.0)  # above the A/B labels
        steps = 32
        # ImGui colours are sRGB-encoded values; its backend linearises them for sRGB targets.
        ramp = linear_to_srgb(heat((np.arange(steps) + 0.5) / steps))
        for i in range(steps):
            r, g, b = ramp[i]
            col = imgui.color_convert_float4_to_u32((r, g, b, 1.0))
            draw.add_rect_filled((x0 + bar_w * i / steps, y0), (x0 + bar_w * (i + 1) / steps, y0 + bar_h), col)
        white = imgui.color_convert_float4_to_u32(WHITE)
        draw.add_rect((x0, y0), (x0 + bar_w, y0 + bar_h), white)
        if v.mode == "cost":
            title = "depth fetches per pixel"
            top = v.cost_scale()
            labels = ["0", f"{top / 2:g}", f"{top:g}+"]
        else:
            tw, th = v.frames.error_texels
            title = f"UV error vs {v.error_reference} in texels ({tw}x{th} map)"
            labels = ["0", f"{v.error_range / 2:.3g}", f"{v.error_range:.3g}+"]
        draw.add_text((x0, y0 - 18), white, title)
        for i, label in enumerate(labels):
            tx = x0 + bar_w * i / 2 - (imgui.calc_text_size(label).x * i / 2)
            draw.add_text((tx, y0 + bar_h + 2), white, label)
        self.drawn_panels.append("legend")

    def _split_labels(self, width) -> None:
        v = self.viewer
        draw = imgui.get_foreground_draw_list()
        x = width * v.state.split_x
        white = imgui.color_convert_float4_to_u32(WHITE)
        yellow = imgui.color_convert_float4_to_u32(YELLOW)
        draw.add_line((x, 0), (x, imgui.get_io().display_size[1]), white, 2.0)
        height = imgui.get_io().display_size[1]
        for (tag, half), cx in zip(v.state.shown(), (x / 2, (x + width) / 2)):
            text = f"{tag}: {half.technique} / {half.filter} ({half.derivatives})"
            size = imgui.calc_text_size(text)
            pos = (cx - size.x / 2, height - size.y - 10)
            draw.add_rect_filled((pos[0] - 6, pos[1] - 4), (pos[0] + size.x + 6, pos[1] + size.y + 4),
                                 imgui.color_convert_float4_to_u32((0, 0, 0, 0.6)))
            draw.add_text(pos, yellow if tag == v.state.active_side else white, text)
        self.drawn_panels.append("split")

    def _status(self, flags, width, height) -> None:
        v = self.viewer
        lines = [(RED, e) for e in v.reloader.errors] if v.reloader else []
        problem = v.current_problem()
        if problem:
            lines.append((RED, problem))
        if v.builds.current is not None:
            lines.append((YELLOW, v.builds.current.line()))
            self.drawn_panels.append("progress")
        lines += [(WHITE, m) for m in v.messages[-3:]]
        if not lines:
            return
        below = v.state.split or v.mode in ("cost", "error")  # the legend and the A/B labels sit at the bottom
        bottom = height - (MARGIN if self.compact and not below else 110 if v.state.split else 80)
        imgui.set_next_window_pos((MARGIN, bottom), imgui.Cond_.always, (0.0, 1.0))
        imgui.set_next_window_size_constraints((0, 0), (max(width - 2 * MARGIN, 60), height / 2))
        imgui.set_next_window_bg_alpha(0.7)
        imgui.begin("Status", None, flags | imgui.WindowFlags_.no_title_bar)
        imgui.push_text_wrap_pos(max(width - 40, 40))  # long paths wrap instead of leaving the screen
        for colour, text in lines:
            imgui.text_colored(colour, text)
        imgui.pop_text_wrap_pos()
        self._record("status")
        imgui.end()

