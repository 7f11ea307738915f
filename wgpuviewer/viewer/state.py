"""What the viewer shows, without a window or a GPU: the scene's techniques, the two halves of the A/B split (each a
``Half``: technique, texture filter, derivative source), which half the keys change, the divider, and the
self-shadowing and depth-offset overrides (both halves: ``shadows``, ``depth_offset``).

The key actions that only change this state are transitions here, so tests drive them directly; whatever needs maps
built or a window (switching to a technique whose maps are missing, vsync, fullscreen) stays in the app.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from wgpuviewer.relief.filters import DERIVATIVE_SOURCES, FILTERS
from wgpuviewer.scene import SHADOW_MODES

from .keys import TECHNIQUE_KEYS, technique_key

SIDES = ("A", "B")
#: What L steps through: None (each material's own ``shadows``), then every mode for all materials.
SHADOW_CHOICES = (None, *SHADOW_MODES)
#: What Z steps through: None (each material's own ``depth_offset``), then off and on for all materials.
DEPTH_OFFSET_CHOICES = (None, False, True)


@dataclass
class Half:
    """One side of the A/B split (the whole screen while it is not split: half A)."""

    technique: str
    filter: str
    derivatives: str


def _next(names: list[str], current: str, step: int = 1) -> str:
    return names[(names.index(current) + step) % len(names)]


@dataclass
class ViewerState:
    techniques: list[str]  # the scene's, in its order (Left/Right step through them)
    halves: dict[str, Half] = field(default_factory=dict)  # "A" and "B"
    split: bool = False
    active_side: str = "A"
    split_x: float = 0.5  # the divider, as a fraction of the width
    shadows: str | None = None  # self-shadowing for every material (scene.SHADOW_MODES); None: each material's own
    depth_offset: bool | None = None  # the hit's depth written for every material (or not); None: each material's own

    @classmethod
    def start(cls, techniques, technique: str, filter: str, derivatives: str) -> ViewerState:
        """A and B both show ``technique`` with the same filter and derivative source: a split starts as a fair
        comparison, and one key on the active half (a technique, F, Shift+F) makes the difference to look at."""
        names = list(techniques)
        if technique not in names:
            names.append(technique)
        return cls(names, {side: Half(technique, filter, derivatives) for side in SIDES})

    @property
    def side(self) -> str:
        """The half the keys change: B only while the screen is split and B is active."""
        return "B" if self.split and self.active_side == "B" else "A"

    @property
    def active(self) -> Half:
        return self.halves[self.side]

    def shown(self) -> list[tuple[str, Half]]:
        """The halves on screen: A alone, or A and B while split."""
        return [(side, self.halves[side]) for side in (SIDES if self.split else SIDES[:1])]

    def show(self, side: str, technique: str) -> None:
        self.halves[side].technique = technique
        if side == "A":
            self.mirror()

    def technique_for_key(self, key: str) -> str | None:
        """The scene's technique that number key ``key`` selects (the registry's ``Technique.key``); None when the
        key's technique is not in this scene."""
        name = TECHNIQUE_KEYS.get(key)
        return name if name in self.techniques else None

    def key_for(self, technique: str) -> str:
        """The key that selects ``technique``: its number key, or the arrows for one without."""
        key = technique_key(technique)
        return key if key in TECHNIQUE_KEYS else "←/→"

    def next_technique(self, step: int) -> str:
        """The scene's technique ``step`` places after the active half's (wrapping around)."""
        return _next(self.techniques, self.active.technique, step)

    def mirror(self) -> None:
        """Unsplit, B follows A (technique, filter, derivative source): a split starts with the same picture on
        both halves. Split, each half keeps its own; joined again, B keeps what it showed until A changes."""
        if not self.split:
            self.halves["B"] = replace(self.halves["A"])

    def cycle_filter(self) -> Half:
        """The active half's next texture filter; returns that half."""
        half = self.active
        half.filter = _next(list(FILTERS), half.filter)
        self.mirror()
        return half

    def cycle_derivatives(self) -> Half:
        """The active half's next derivative source; returns that half."""
        half = self.active
        half.derivatives = _next(list(DERIVATIVE_SOURCES), half.derivatives)
        self.mirror()
        return half

    def cycle_shadows(self) -> str | None:
        """The next self-shadowing override (SHADOW_CHOICES); returns it."""
        self.shadows = SHADOW_CHOICES[(SHADOW_CHOICES.index(self.shadows) + 1) % len(SHADOW_CHOICES)]
        return self.shadows

    @property
    def shadows_label(self) -> str:
        """How the HUD names the override: 'materials' (each its own), or the mode for all."""
        return "materials" if self.shadows is None else self.shadows

    def cycle_depth_offset(self) -> bool | None:
        """The next depth-offset override (DEPTH_OFFSET_CHOICES); returns it."""
        i = DEPTH_OFFSET_CHOICES.index(self.depth_offset)
        self.depth_offset = DEPTH_OFFSET_CHOICES[(i + 1) % len(DEPTH_OFFSET_CHOICES)]
        return self.depth_offset

    @property
    def depth_offset_label(self) -> str:
        """How the HUD names the override: 'materials' (each its own), 'off' or 'on' for all."""
        return "materials" if self.depth_offset is None else ("on" if self.depth_offset else "off")

    def toggle_split(self) -> None:
        """Split or join the screen; either way the keys change half A next."""
        self.split = not self.split
        self.active_side = "A"

    def switch_half(self) -> None:
        self.active_side = "B" if self.active_side == "A" and self.split else "A"
