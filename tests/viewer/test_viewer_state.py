"""The viewer's state without a window: technique keys from the registry, filter and derivative cycling on the active
half, the A/B split; and the key table stays the one source of the technique keys."""

from __future__ import annotations

import subprocess
import sys

from wgpuviewer.relief.filters import DERIVATIVE_SOURCES, FILTERS
from wgpuviewer.techniques import TECHNIQUES
from wgpuviewer.viewer.keys import PRESSED, TECHNIQUE_KEYS
from wgpuviewer.viewer.state import Half, ViewerState

FIRST_FILTER, SECOND_FILTER = list(FILTERS)[:2]
FIRST_SOURCE, SECOND_SOURCE = list(DERIVATIVE_SOURCES)[:2]


def state(techniques=("basic", "normal", "pom"), technique="basic") -> ViewerState:
    return ViewerState.start(techniques, technique, FIRST_FILTER, FIRST_SOURCE)


def test_the_state_needs_neither_a_gpu_driver_nor_a_toolkit():
    # The technique registry's folders declare their texture slots, so the wgpu module is imported; its native
    # driver (what needs a GPU or lavapipe) is not loaded.
    code = ("import sys; import wgpuviewer.viewer.state; "
            "print(sorted(m for m in ('wgpu.backends.wgpu_native', 'rendercanvas', 'glfw', 'imgui_bundle') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_a_and_b_start_with_the_same_technique_filter_and_derivative_source():
    s = state(technique="pom")
    assert s.halves == {"A": Half("pom", FIRST_FILTER, FIRST_SOURCE), "B": Half("pom", FIRST_FILTER, FIRST_SOURCE)}
    assert not s.split and s.side == "A" and [side for side, _ in s.shown()] == ["A"]
    assert state(technique="relief").techniques == ["basic", "normal", "pom", "relief"]  # not listed: added last


def test_b_follows_a_while_unsplit_so_a_split_opens_on_the_same_picture():
    s = state(technique="basic")
    s.show("A", "normal")
    s.cycle_filter()
    s.toggle_split()  # two filters compared in three keys: B, Tab, F
    assert s.halves["A"] == s.halves["B"] == Half("normal", SECOND_FILTER, FIRST_SOURCE)
    s.switch_half()
    s.cycle_filter()
    assert s.halves["A"].filter == SECOND_FILTER and s.halves["B"].filter != SECOND_FILTER
    s.show("A", "pom")  # split: B keeps its own
    assert s.halves["B"].technique == "normal"
    s.toggle_split()
    assert s.halves["B"].technique == "normal"  # joined: B keeps what it showed until A changes
    s.show("A", "basic")
    assert s.halves["B"] == s.halves["A"] == Half("basic", SECOND_FILTER, FIRST_SOURCE)


def test_number_keys_pick_by_the_registry_key_in_every_scene():
    assert set(TECHNIQUE_KEYS) == set("1234567890")
    for key, name in TECHNIQUE_KEYS.items():
        assert TECHNIQUES[name].key == key and PRESSED[key].action == "pick_technique"
    s = state(("basic", "pom", "relief"))
    assert s.technique_for_key(TECHNIQUES["pom"].key) == "pom"  # pom is second here, its key is still its own
    assert s.technique_for_key(TECHNIQUES["relief"].key) == "relief"
    assert s.technique_for_key(TECHNIQUES["normal"].key) is None  # not in this scene
    assert s.key_for("pom") == TECHNIQUES["pom"].key
    keyless = next(name for name, t in TECHNIQUES.items() if t.key == "-")
    assert s.key_for(keyless) == "←/→"


def test_arrows_step_through_the_scene_from_the_active_half():
    s = state(("basic", "normal", "pom"), "basic")
    assert s.next_technique(1) == "normal" and s.next_technique(-1) == "pom"
    s.toggle_split()
    s.switch_half()
    s.show("B", "normal")  # B (normal) is active
    assert s.next_technique(1) == "pom"


def test_filter_and_derivatives_cycle_on_the_active_half_and_b_follows_a_while_unsplit():
    s = state()
    assert s.cycle_filter() is s.halves["A"]
    assert s.halves["A"].filter == s.halves["B"].filter == SECOND_FILTER
    s.cycle_derivatives()
    assert s.halves["A"].derivatives == s.halves["B"].derivatives == SECOND_SOURCE
    for _ in FILTERS:  # a full cycle comes back
        s.cycle_filter()
    assert s.halves["A"].filter == SECOND_FILTER

    s.toggle_split()
    s.switch_half()
    assert s.side == "B"
    s.cycle_filter()
    s.cycle_derivatives()
    assert s.halves["A"] == Half("basic", SECOND_FILTER, SECOND_SOURCE)
    assert s.halves["B"].filter != SECOND_FILTER and s.halves["B"].derivatives != SECOND_SOURCE


def test_split_on_and_off():
    s = state()
    s.switch_half()  # unsplit: there is only A
    assert s.side == "A" and s.active_side == "A"
    s.toggle_split()
    assert s.split and [side for side, _ in s.shown()] == ["A", "B"]
    s.switch_half()
    assert s.side == "B" and s.active is s.halves["B"]
    s.show("B", "pom")
    s.toggle_split()  # joined: the keys change A, B keeps what it showed
    assert not s.split and s.side == "A" and s.halves["B"].technique == "pom"
    s.toggle_split()
    assert s.active_side == "A"  # a new split starts on A


def test_the_split_draws_two_scissored_passes_that_tile_the_frame():
    from wgpuviewer.viewer.frames import scene_passes

    assert scene_passes(["a"], None, 100, 50) == [("a", None)]
    assert scene_passes(["a", "b"], 0.25, 100, 50) == [("a", (0, 0, 25, 50)), ("b", (25, 0, 75, 50))]
    for split_x in (0.0, 1.0):  # the divider at an edge still leaves each half a column
        (_, (_, _, left, _)), (_, (x, _, right, _)) = scene_passes(["a", "b"], split_x, 100, 50)
        assert left >= 1 and right >= 1 and x == left and left + right == 100


def test_every_key_action_is_a_viewer_method_taking_the_key_pressed():
    import inspect

    from wgpuviewer.viewer.app import Viewer
    from wgpuviewer.viewer.keys import CONTROLS

    actions = [c.action for c in CONTROLS if c.action]
    assert actions and all(list(inspect.signature(getattr(Viewer, a)).parameters) == ["self", "key"] for a in actions)
