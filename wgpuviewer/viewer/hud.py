"""The viewer's on-screen UI (Dear ImGui through ``wgpu.utils.imgui``, package ``imgui-bundle``).

Panels: statistics (X), info with the technique's description and live parameters and the texture filter (F,
Shift+F: its derivative source) with its parameters, one section per A/B half (the active one open), help (F1),
a colour legend on a backdrop in the cost and error views with each half's mean and p95, labels of the A/B halves,
status and shader errors. H hides everything. Panels with a title bar fit their content, collapse and move, and are
kept on screen when they grow or the window shrinks. The HUD draws into the frame in its own render pass, after the
scene, in a font that has every glyph it prints (``font_path``).
"""

from __future__ import annotations

try:
    import imgui_bundle
    from imgui_bundle import imgui
    from wgpu.utils.imgui import ImguiRenderer
except ImportError:  # the viewer then runs without a HUD (window title only)
    imgui = None
    ImguiRenderer = None

import functools
from pathlib import Path

import numpy as np

from wgpuviewer.core.color import heat, linear_to_srgb
from wgpuviewer.relief.filters import DERIVATIVE_SOURCES, FILTERS, get_filter
from wgpuviewer.relief.maps import height_scale_adjustable
from wgpuviewer.techniques import get_technique

from .keys import CONTROLS

AVAILABLE = imgui is not None

WHITE = (1.0, 1.0, 1.0, 1.0)
YELLOW = (1.0, 0.85, 0.3, 1.0)
RED = (1.0, 0.35, 0.3, 1.0)
GREY = (0.7, 0.7, 0.7, 1.0)
#: Backgrounds. The frame is sRGB, so imgui blends in linear light: a 0.6 black over white still looks mid-grey.
#: These keep grey and white text legible over a white heat map.
BACKDROP = (0.0, 0.0, 0.0, 0.85)
PANEL_ALPHA = 0.9
MARGIN = 8.0
PAD = 6.0  # inside the legend's and the A/B labels' backdrops
FONT_SIZE = 15.0
#: Widths in logical pixels: the info panel's sliders and combos, its wrapped descriptions.
ITEM_WIDTH = 160.0
TEXT_WIDTH = 340.0
#: The key list opens between the side panels when they leave it this much room (logical pixels).
HELP_MIN_WIDTH = 420.0
#: Below this window size (logical pixels) the HUD is compact.
COMPACT_SIZE = (640, 400)


def font_path() -> Path:
    """Inconsolata (shipped with imgui-bundle, SIL Open Font License): it has every glyph the HUD prints (en
    dashes, arrows, degrees, ellipses); imgui's built-in font has only Latin-1 and showed the others as '?'."""
    return Path(imgui_bundle.__file__).parent / "assets" / "fonts" / "Inconsolata-Medium.ttf"


def summary_line(tag: str, summary, unit: str) -> str:
    """A legend line of one half: its mean and p95 (``stats.Summary``; None: nothing drawn there)."""
    prefix = f"{tag}: " if tag else ""
    if summary is None:
        return f"{prefix}nothing drawn"
    return f"{prefix}mean {summary.mean:.3g}, p95 {summary.p95:.3g} {unit}"


def budget_line(technique: str, params: dict) -> str | None:
    """The pixel budget of a technique with a screen-space error budget (``max_error_px``) as the HUD shows it, with
    the texel budget it starts from; None for a technique without one."""
    if "max_error_px" not in {p.name for p in get_technique(technique).params}:
        return None
    pixels, texels = params.get("max_error_px", 0.0), params.get("max_error")
    floor = f"{texels:g} texel" if texels is not None else "the texel budget"
    if not pixels:
        return f"pixel budget off (max_error_px 0): {floor} everywhere"
    return f"pixel budget {pixels:g} px (at least {floor})"


def _budget_tag(technique: str, params: dict) -> str:
    """The info panel's title's note of a pixel budget (the title stays visible when the panel is collapsed)."""
    pixels = params.get("max_error_px") if budget_line(technique, params) is not None else None
    return f" ({pixels:g} px)" if pixels else ""


@functools.lru_cache(maxsize=16)
def panel_lines(renderer, technique: str, params: tuple) -> list[str]:
    """A technique's own lines on the renderer's scene (``Technique.panel_lines``; ``params``: its parameters as
    sorted (name, value) pairs), e.g. what auto chooses per view-angle range on each material."""
    return get_technique(technique).panel_lines(renderer.scene.materials, dict(params))


class Hud:
    def __init__(self, viewer):
        self.viewer = viewer
        self.imgui = ImguiRenderer(viewer.gpu.device, viewer.window.canvas)
        io = imgui.get_io()
        io.set_ini_filename("")  # window positions are not persisted next to the user's cwd
        # imgui loads the glyphs a frame uses as it meets them: the whole font, no glyph ranges to keep up to date
        io.font_default = io.fonts.add_font_from_file_ttf(str(font_path()), FONT_SIZE)
        self.drawn_panels: list[str] = []  # what the last frame showed (tests, debugging)
        self.rects: dict[str, tuple[float, float, float, float]] = {}  # panel -> (x, y, w, h) in the last frame
        self._previous: dict[str, tuple[float, float, float, float]] = {}
        self._docked: dict[str, float | None] = {}  # panel -> the right edge it was last put at (follows the window's)
        self._open_side: str | None = None  # the half whose section was opened for the active one
        self._help_span = (0.0, 0.0)  # the key list's room (left, right), chosen when it opens

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

    def _place(self, name: str, pos, pivot, width: float, height: float, appearing: bool = False) -> None:
        """Before a movable panel: at ``pos`` (with ``pivot``) when it first appears (``appearing``: each time it
        appears); later where the user put it, moved back on screen when it has grown past an edge or the window has
        shrunk; never larger than the window (a taller one scrolls). A panel put at the right edge stays there as
        its width or the window's changes, until the user moves it away."""
        imgui.set_next_window_size_constraints((0, 0), (max(width - 2 * MARGIN, 60), max(height - 2 * MARGIN, 60)))
        last = self._previous.get(name)
        if last is None:
            imgui.set_next_window_pos(pos, imgui.Cond_.appearing if appearing else imgui.Cond_.first_use_ever, pivot)
            if pivot[0] == 1.0:
                self._docked[name] = None  # imgui sizes a new panel in a hidden frame first: no edge to compare yet
            return
        if self._docked.get(name, 0.0) is None:  # the first frame shown: where it was put, if it was
            self._docked[name] = pos[0]
            return
        x, y, w, h = last
        if name in self._docked and abs(x + w - self._docked[name]) < 1.0:  # docked: the right edge where it was put
            self._docked[name] = width - MARGIN
            imgui.set_next_window_pos((width - MARGIN, min(y, max(height - MARGIN - h, MARGIN))), imgui.Cond_.always,
                                      (1.0, 0.0))
            return
        self._docked.pop(name, None)
        nx = min(max(x, MARGIN), max(width - MARGIN - w, MARGIN))
        ny = min(max(y, MARGIN), max(height - MARGIN - h, MARGIN))
        if (nx, ny) != (x, y):
            imgui.set_next_window_pos((nx, ny), imgui.Cond_.always)

    def build(self) -> None:
        v = self.viewer
        self.drawn_panels = []
        self._previous, self.rects = self.rects, {}
        if not v.show_hud:
            return
        width, height = imgui.get_io().display_size
        #: Small windows (e.g. 320x240): short statistics, the technique panel collapsed beside them, no overlap.
        self.compact = width < COMPACT_SIZE[0] or height < COMPACT_SIZE[1]
        flags = imgui.WindowFlags_.always_auto_resize | imgui.WindowFlags_.no_focus_on_appearing
        if v.show_stats:
            self._stats_panel(flags, width, height)
        self._info_panel(flags, width, height)
        if v.show_help:
            self._help_panel(flags, width, height)
        # The bottom of the screen, from the edge up: the A/B labels, the legend, the status lines.
        bottom = height  # where the free space ends
        if v.state.split:
            bottom = self._split_labels(width, height)
        if v.mode in ("cost", "error"):
            bottom = self._legend(width, bottom - MARGIN)
        self._status(flags, width, height, bottom - MARGIN)

    def _stats_panel(self, flags, width, height) -> None:
        v = self.viewer
        if self.compact:
            imgui.set_next_window_pos((MARGIN, MARGIN), imgui.Cond_.always)
            imgui.set_next_window_size_constraints((0, 0), (width / 2 - 1.5 * MARGIN, 1e4))
        else:
            self._place("stats", (MARGIN, MARGIN), (0.0, 0.0), width, height)
        imgui.set_next_window_bg_alpha(PANEL_ALPHA)
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

    def _wrapped(self, colour, text: str) -> None:
        """``text`` wrapped at the panel's text width (compact: at the panel's edge, its width is fixed)."""
        imgui.push_text_wrap_pos(0.0 if self.compact else imgui.get_cursor_pos_x() + TEXT_WIDTH)
        imgui.text_colored(colour, text)
        imgui.pop_text_wrap_pos()

    def _info_panel(self, flags, width, height) -> None:
        v = self.viewer
        if self.compact:  # beside the statistics, collapsed to its title (click to open)
            panel = width / 2 - 1.5 * MARGIN
            imgui.set_next_window_pos((width - MARGIN, MARGIN), imgui.Cond_.always, (1.0, 0.0))
            imgui.set_next_window_size((panel, 0), imgui.Cond_.always)
            imgui.set_next_window_collapsed(True, imgui.Cond_.first_use_ever)
            flags = imgui.WindowFlags_.no_focus_on_appearing
            self._docked["info"] = width - MARGIN  # a larger window keeps it at the right edge
        else:
            self._place("info", (width - MARGIN, MARGIN), (1.0, 0.0), width, height)
        imgui.set_next_window_bg_alpha(PANEL_ALPHA)
        state = v.state
        a = state.halves["A"].technique
        title = f"{state.key_for(a)} {a}{_budget_tag(a, v.technique_params(a))}" + (
            f" | {state.halves['B'].technique}" if state.split else "")
        opened = imgui.begin(f"{title}###Technique", None, flags)[0]
        # Right after begin the last item is the title bar, active while the panel is dragged: it leaves the edge.
        if imgui.is_item_active() and imgui.is_mouse_dragging(imgui.MouseButton_.left):
            self._docked.pop("info", None)
        if not opened:
            self._record("info")  # collapsed: the title bar alone
            imgui.end()
            return
        imgui.push_item_width(panel / 2 if self.compact else ITEM_WIDTH)
        # Split: one section per half, the active one open (Tab opens the other); either can be opened by a click.
        reopen = state.split and self._open_side != state.active_side
        self._open_side = state.active_side if state.split else None
        for tag, half in state.shown():
            t = get_technique(half.technique)
            heading = f"{state.key_for(t.name)}  {t.name}"
            if state.split:
                if reopen:
                    imgui.set_next_item_open(tag == state.active_side, imgui.Cond_.always)
                active = tag == state.active_side
                imgui.push_style_color(imgui.Col_.text, YELLOW if active else WHITE)
                opened = imgui.collapsing_header(f"{tag}: {heading} / {half.filter}###half{tag}")
                imgui.pop_style_color()
                if not opened:
                    continue
            else:
                imgui.text(heading)
            self._half(half, tag)
            imgui.separator()
        imgui.text(f"shadows (L): {state.shadows_label}   depth offset (Z): {state.depth_offset_label}")
        imgui.text(f"render scale (U): {self.viewer.render_scale_label}")
        for i, mode in enumerate(("color", "cost", "error")):
            if i:
                imgui.same_line()
            if imgui.radio_button(mode, v.mode == mode):
                v.set_mode(mode)
        if v.mode == "error":
            _, v.error_range = imgui.slider_float("error range (texels)", v.error_range, 0.1, 32.0, "%.1f",
                                                  imgui.SliderFlags_.logarithmic)
        if imgui.collapsing_header("camera and display"):
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

    def _half(self, half, tag: str) -> None:
        """One half's section: its technique's description, parameters and own lines (what auto picks), its filter."""
        v = self.viewer
        t = get_technique(half.technique)
        self._wrapped(GREY, t.description)
        budget = budget_line(t.name, v.technique_params(t.name))
        if budget is not None:
            imgui.text_colored(YELLOW, budget)
        self._params(t.name, tag)
        if t.panel_lines is not None:
            for line in panel_lines(v.renderer, t.name, tuple(sorted(v.technique_params(t.name).items()))):
                imgui.text_colored(GREY, line)
        self._filter(half, tag)

    def _filter(self, half, tag: str) -> None:
        """The half's texture filter (a combo, F cycles it), its derivative source (Shift+F) and parameters."""
        self._choice(half, "filter", f"filter (F)##{tag}", FILTERS)
        self._choice(half, "derivatives", f"derivatives (Shift+F)##{tag}", DERIVATIVE_SOURCES)
        f = get_filter(half.filter)
        self._sliders(f.params, self.viewer.filter_params[f.name], f"{tag}:{f.name}")

    def _choice(self, half, attribute: str, label: str, registry: dict) -> None:
        """A combo choosing the half's ``attribute`` among the names of ``registry`` (the other half follows where
        it mirrors this one); hovered, the chosen entry's description."""
        names = list(registry)
        changed, index = imgui.combo(label, names.index(getattr(half, attribute)), names)
        if changed:
            setattr(half, attribute, names[index])
            self.viewer.state.mirror()
        if imgui.is_item_hovered():
            imgui.set_tooltip(registry[getattr(half, attribute)].description)

    def _help_panel(self, flags, width, height) -> None:
        """The key list, opened in the room between the statistics and the info panel when they leave enough (else
        over the middle of the window), its descriptions wrapped to fit there."""
        if "help" not in self._previous:  # opening
            x, _, w, _ = self.rects.get("stats", (0.0, 0.0, 0.0, 0.0))
            left, right = x + w, self.rects.get("info", (width,))[0]
            self._help_span = (left, right) if right - left >= HELP_MIN_WIDTH + 2 * MARGIN else (0.0, width)
        left, right = self._help_span
        self._place("help", ((left + right) / 2, height / 2), (0.5, 0.5), width, height, appearing=True)
        imgui.set_next_window_bg_alpha(PANEL_ALPHA)
        imgui.begin("Keys (F1 closes)", None, flags)
        style = imgui.get_style()
        column = style.window_padding.x + max(imgui.calc_text_size(c.label).x for c in CONTROLS) + 2 * style.item_spacing.x
        room = right - left - 2 * MARGIN - style.window_padding.x - column
        longest = max(imgui.calc_text_size(c.help).x for c in CONTROLS)
        for control in CONTROLS:
            imgui.text_colored(YELLOW, control.label)
            imgui.same_line(column)
            imgui.push_text_wrap_pos(column + max(min(longest, room), 80))
            imgui.text(control.help)
            imgui.pop_text_wrap_pos()
        self._record("help")
        imgui.end()

    def _legend(self, width, bottom) -> float:
        """The heat ramp, its scale and each half's mean and p95 on a backdrop, ending at ``bottom``; returns its
        top."""
        v = self.viewer
        draw = imgui.get_foreground_draw_list()
        white = imgui.color_convert_float4_to_u32(WHITE)
        line_h = imgui.get_text_line_height()
        if v.mode == "cost":
            titles = ("depth fetches per pixel", "fetches per pixel")
            top = v.cost_scale()
            labels = ["0", f"{top / 2:g}", f"{top:g}+"]
            unit = "fetches"
        else:
            tw, th = v.frames.error_texels
            titles = (f"UV error vs {v.error_reference} in texels ({tw}x{th} map)", "UV error in texels")
            labels = ["0", f"{v.error_range / 2:.3g}", f"{v.error_range:.3g}+"]
            unit = "texels"
        room = width - 2 * MARGIN - 2 * PAD
        title = next((t for t in titles if imgui.calc_text_size(t).x <= room), titles[-1])
        split = v.state.split
        lines = []
        if len(v.heat_summaries) == len(v.state.shown()):  # measured for what is shown (a split just toggled: not yet)
            for (tag, _), summary in zip(v.state.shown(), v.heat_summaries):
                lines.append(summary_line(tag if split else "", summary, unit))
        if split and v.mode == "cost" and v.cost_scale("B") != v.cost_scale():
            lines.append(f"B: full heat at {v.cost_scale('B'):g}")  # each half is painted on its own scale
        bar_w = min(320.0, room)
        box_w = min(max([bar_w] + [imgui.calc_text_size(t).x for t in (title, *lines)]), room) + 2 * PAD
        bar_h = 14.0
        box_h = PAD + line_h + 4 + bar_h + 2 + line_h + len(lines) * line_h + PAD
        x0, y0 = MARGIN, bottom - box_h
        draw.add_rect_filled((x0, y0), (x0 + box_w, bottom), imgui.color_convert_float4_to_u32(BACKDROP), 4.0)
        x, y = x0 + PAD, y0 + PAD
        draw.add_text((x, y), white, title)
        y += line_h + 4
        steps = 32
        # ImGui colours are sRGB-encoded values; its backend linearises them for sRGB targets.
        ramp = linear_to_srgb(heat((np.arange(steps) + 0.5) / steps))
        for i in range(steps):
            r, g, b = ramp[i]
            col = imgui.color_convert_float4_to_u32((r, g, b, 1.0))
            draw.add_rect_filled((x + bar_w * i / steps, y), (x + bar_w * (i + 1) / steps, y + bar_h), col)
        draw.add_rect((x, y), (x + bar_w, y + bar_h), white)
        y += bar_h + 2
        for i, label in enumerate(labels):
            draw.add_text((x + bar_w * i / 2 - imgui.calc_text_size(label).x * i / 2, y), white, label)
        for line in lines:
            y += line_h
            draw.add_text((x, y), white, line)
        self.rects["legend"] = (x0, y0, box_w, box_h)
        self.drawn_panels.append("legend")
        return y0

    def _split_labels(self, width, height) -> float:
        """The divider and each half's label at the bottom; returns the labels' top."""
        v = self.viewer
        draw = imgui.get_foreground_draw_list()
        x = width * v.state.split_x
        white = imgui.color_convert_float4_to_u32(WHITE)
        yellow = imgui.color_convert_float4_to_u32(YELLOW)
        draw.add_line((x, 0), (x, height), white, 2.0)
        top = height
        for (tag, half), (left, right) in zip(v.state.shown(), ((0, x), (x, width))):
            # the longest label that fits its half
            texts = (f"{tag}: {half.technique} / {half.filter} ({half.derivatives})",
                     f"{tag}: {half.technique} / {half.filter}", f"{tag}: {half.technique}", tag)
            room = right - left - 2 * PAD - 4
            text = next((t for t in texts if imgui.calc_text_size(t).x <= room), tag)
            size = imgui.calc_text_size(text)
            pos = ((left + right - size.x) / 2, height - size.y - MARGIN - PAD / 2)
            draw.add_rect_filled((pos[0] - PAD, pos[1] - PAD / 2), (pos[0] + size.x + PAD, pos[1] + size.y + PAD / 2),
                                 imgui.color_convert_float4_to_u32(BACKDROP), 4.0)
            draw.add_text(pos, yellow if tag == v.state.active_side else white, text)
            top = min(top, pos[1] - PAD / 2)
        self.rects["split"] = (0.0, top, width, height - top)  # the band of the labels
        self.drawn_panels.append("split")
        return top

    def _status(self, flags, width, height, bottom) -> None:
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
        imgui.set_next_window_pos((MARGIN, bottom), imgui.Cond_.always, (0.0, 1.0))
        imgui.set_next_window_size_constraints((0, 0), (max(width - 2 * MARGIN, 60), height / 2))
        imgui.set_next_window_bg_alpha(PANEL_ALPHA)
        imgui.begin("Status", None, flags | imgui.WindowFlags_.no_title_bar)
        imgui.push_text_wrap_pos(max(width - 40, 40))  # long paths wrap instead of leaving the screen
        for colour, text in lines:
            imgui.text_colored(colour, text)
        imgui.pop_text_wrap_pos()
        self._record("status")
        imgui.end()
