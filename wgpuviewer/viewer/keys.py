"""The viewer's controls, in one table: what the keys (and the mouse) do. ``Viewer.press`` dispatches on it, the
help panel (F1) lists it, ``--keys`` checks against it, and the keys table of docs/usage.md is generated from it
(``markdown_table``; a test compares the two).

Key names are rendercanvas's event keys: Shift+D arrives as "D", so "d" (strafe, held) and "D" (cost view) are
different keys. The number keys pick techniques by the registry's ``Technique.key`` (the same key in every scene).

A scripted run's keys (``--keys``, ``parse_script``) are the pressed keys, one per frame, and the fly keys held for
a time: ``W:0.5`` holds W (either case) for 0.5 seconds of camera motion, played at a fixed
``SCRIPT_FRAME_SECONDS`` per frame whatever a frame really takes, so a script moves the camera the same on every
machine: 15 frames of 1/30 s here, moving the fly camera 0.5 s x its move speed forward in all.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

from wgpuviewer.core.errors import UserError
from wgpuviewer.techniques import TECHNIQUES, get_technique

#: Number key -> the technique it picks (techniques whose key is "-" are reached with the arrows).
TECHNIQUE_KEYS = {t.key: name for name, t in TECHNIQUES.items() if t.key != "-"}


def technique_key(name: str) -> str:
    return get_technique(name).key


@dataclass(frozen=True)
class Control:
    label: str  # as the help panel and docs/usage.md show it
    help: str
    keys: tuple[str, ...] = ()  # event keys that trigger it; () for mouse controls
    action: str = ""  # the Viewer method called with the key pressed ("" for held and mouse controls)


#: Held keys of the fly camera: direction (right, up, forward) each one moves in while held.
FLY_KEYS = {"w": (0, 0, 1), "a": (-1, 0, 0), "s": (0, 0, -1), "d": (1, 0, 0), "q": (0, -1, 0), "e": (0, 1, 0)}
#: How messages name them.
FLY_LABEL = " ".join(FLY_KEYS).upper()

CONTROLS = (
    Control("1–9, 0", "pick the technique (in A/B: of the active half); 0 is the tenth",
            tuple(TECHNIQUE_KEYS), "pick_technique"),
    Control("←/→", "previous / next technique (also past the tenth)", ("ArrowLeft", "ArrowRight"), "cycle_technique"),
    Control("W A S D, Q E", "fly forward/left/back/right, down/up (while held)", tuple(FLY_KEYS)),
    Control("left drag", "look around (fly) / orbit (orbit camera); drags the A/B divider"),
    Control("wheel", "zoom (orbit) / move speed (fly)"),
    Control("O", "fly ↔ orbit camera", ("o", "O"), "toggle_camera"),
    Control("R", "reset the camera", ("r", "R"), "reset_camera"),
    Control("Shift+D", "cost view: depth fetches per pixel as a heat map, with a legend", ("D",), "toggle_cost"),
    Control("Shift+E", "error view: UV error in texels against POM with 512 layers, as a heat map", ("E",),
            "toggle_error"),
    Control("M", "cycle colour / cost / error", ("m", "M"), "cycle_mode"),
    Control("F", "next texture filter (in A/B: of the active half); the HUD names it", ("f",), "cycle_filter"),
    Control("Shift+F", "next derivative source of the filter's footprint (uv, displaced, analytic)", ("F",),
            "cycle_derivatives"),
    Control("L", "self-shadowing: the materials' own, then off, hard, soft for every material; the HUD names it",
            ("l", "L"), "cycle_shadows"),
    Control("Z", "depth offset (the traced hit's depth): the materials' own, then off, on for every material; the HUD "
            "names it", ("z", "Z"), "cycle_depth_offset"),
    Control("B", "A/B split between two techniques or filters; drag the divider", ("b", "B"), "toggle_split"),
    Control("Tab", "the half of the A/B split the keys change", ("Tab",), "switch_half"),
    Control("P", "save a screenshot PNG (scene only) in the current directory", ("p", "P"), "request_screenshot"),
    Control("C", "reset the statistics", ("c", "C"), "reset_stats"),
    Control("X", "show/hide the statistics (FPS current/min/avg/max, frame time, GPU time)", ("x", "X"),
            "toggle_stats"),
    Control("H", "hide/show all UI", ("h", "H"), "toggle_hud"),
    Control("F1", "show/hide the keys", ("F1",), "toggle_help"),
    Control("V", "vsync on/off", ("v", "V"), "toggle_vsync"),
    Control("F11", "fullscreen on/off", ("F11",), "toggle_fullscreen"),
    Control("U", "render scale: auto (on a software adapter, the scene at the fraction of the window that holds ~15 "
            "frames per second), 1, 0.75, 0.5, 0.35, 0.25; the HUD shows it", ("u", "U"), "cycle_render_scale"),
    Control("F5", "reload shaders now (edited `wgsl/` files also reload by themselves)", ("F5",), "reload_shaders"),
    Control("Esc", "quit", ("Escape",), "quit"),
)

#: Event key -> the control it triggers on press.
PRESSED = {key: control for control in CONTROLS if control.action for key in control.keys}


def markdown_table() -> str:
    """The keys table of docs/usage.md."""
    rows = ["| key | action |", "|---|---|"]
    rows += [f"| {c.label} | {c.help} |" for c in CONTROLS]
    return "\n".join(rows)


#: A scripted hold plays at this many seconds of camera motion per frame.
SCRIPT_FRAME_SECONDS = 1 / 30
#: The longest hold a script may give (1800 frames).
MAX_HOLD_SECONDS = 60.0


@dataclass(frozen=True)
class ScriptStep:
    """One frame of a scripted run: ``key`` pressed (``seconds`` 0), or the fly key ``key`` held for ``seconds``
    of camera motion."""

    key: str
    seconds: float = 0.0


def parse_script(items: Iterable[str]) -> list[ScriptStep]:
    """The frames of ``--keys`` items (``2``, ``ArrowRight``, ``W:0.5``): a press is one frame, a hold of S seconds
    ceil(S / SCRIPT_FRAME_SECONDS) frames sharing S evenly. A bad item is a UserError naming it and the fix."""
    steps: list[ScriptStep] = []
    for item in items:
        key, colon, duration = item.partition(":")
        fly = key.lower() if len(key) == 1 and key.lower() in FLY_KEYS else None
        if not colon:
            if key in PRESSED:
                steps.append(ScriptStep(key))
                continue
            if fly:
                raise UserError(f"--keys: {key!r} is a fly key, held for a time: give the seconds, e.g. {key}:0.5")
            raise UserError(f"--keys: unknown key {key!r}; known: {', '.join(sorted(PRESSED))}, and the fly keys "
                            f"{FLY_LABEL} held for seconds (W:0.5)")
        if not fly:
            raise UserError(f"--keys: {item!r}: only the fly keys {FLY_LABEL} are held for a time; "
                            f"a pressed key is given alone (e.g. 2,W:0.5)")
        try:
            seconds = float(duration)
        except ValueError:
            seconds = math.nan
        if not (math.isfinite(seconds) and 0 < seconds <= MAX_HOLD_SECONDS):
            raise UserError(f"--keys: {item!r}: expected {key}:SECONDS with SECONDS in (0, {MAX_HOLD_SECONDS:g}], "
                            f"e.g. {key}:0.5")
        frames = max(1, math.ceil(seconds / SCRIPT_FRAME_SECONDS - 1e-9))
        steps += [ScriptStep(fly, seconds / frames)] * frames
    return steps
