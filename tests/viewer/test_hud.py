"""The HUD: a font with every glyph it prints, and a session under a (virtual) X display in the A/B split's cost and
error views with the key list open: panels on screen, the bottom stack (labels, legend, status) without overlap, the
legend's mean and p95 per half, no ERROR logged."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from imgui_bundle import imgui

from wgpuviewer.relief.filters import DERIVATIVE_SOURCES, FILTERS
from wgpuviewer.techniques import TECHNIQUES
from wgpuviewer.viewer.hud import budget_line, font_path, summary_line
from wgpuviewer.viewer.keys import CONTROLS
from wgpuviewer.viewer.state import ViewerState
from wgpuviewer.viewer.stats import Summary


def printed_texts() -> list[str]:
    """What the HUD prints from the registries and the key table (the rest is built from these and ASCII)."""
    texts = [text for c in CONTROLS for text in (c.label, c.help)]
    for t in TECHNIQUES.values():
        texts += [t.name, t.description, *(p.doc for p in t.params)]
    for f in FILTERS.values():
        texts += [f.name, f.description, *(p.doc for p in f.params)]
    texts += [d.description for d in DERIVATIVE_SOURCES.values()]
    state = ViewerState.start(list(TECHNIQUES), "pom", next(iter(FILTERS)), next(iter(DERIVATIVE_SOURCES)))
    texts += [state.key_for(name) for name in TECHNIQUES]
    budgets = [budget_line(name, {**t.defaults(), **extra}) for name, t in TECHNIQUES.items()
               for extra in ({}, {"max_error_px": 0.5})]
    return texts + ["0.0-12.5°: pom", summary_line("A", Summary(1.5, 3.0), "texels"), *filter(None, budgets)]


def test_the_hud_shows_the_pixel_budget_of_a_technique_that_has_one():
    budgeted = [name for name, t in TECHNIQUES.items() if "max_error_px" in {p.name for p in t.params}]
    assert "auto" in budgeted
    auto = TECHNIQUES["auto"].defaults()
    assert budget_line("auto", {**auto, "max_error": 1.0, "max_error_px": 0.5}) == \
        "pixel budget 0.5 px (at least 1 texel)"
    assert budget_line("auto", {**auto, "max_error": 0.5, "max_error_px": 0.0}).startswith("pixel budget off")
    assert budget_line("pom", TECHNIQUES["pom"].defaults()) is None


@pytest.fixture()
def fonts():
    context = imgui.create_context()
    try:
        atlas = imgui.get_io().fonts
        yield atlas.add_font_from_file_ttf(str(font_path()), 15.0), atlas.add_font_default()
    finally:
        imgui.destroy_context(context)


def test_the_hud_font_has_every_glyph_the_hud_prints(fonts):
    hud_font, builtin = fonts
    characters = set("".join(printed_texts()))
    assert {"–", "←", "→", "↔", "°"} <= characters  # the help list and auto's ranges print these
    assert not [c for c in sorted(characters) if not hud_font.is_glyph_in_font(ord(c))]
    assert [c for c in "–←→↔" if not builtin.is_glyph_in_font(ord(c))] == list("–←→↔")  # imgui's own showed '?'


SESSION = """
import json, logging, sys
logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
from wgpuviewer.scene import default_scene_path, load_scene
from wgpuviewer.viewer.app import Viewer

viewer = Viewer(load_scene(default_scene_path()), "pom", None, size=(640, 400), scripted=True)
script = ["V", "B", "Tab", "2", "D", "F1", None, None, "E", None, None, None]  # V: a status line
seen = {}

def frame():
    key = script.pop(0) if script else None
    if key:
        viewer.press(key)
    viewer.draw()
    if not script or script[0] == "E":  # the last frame of each view
        seen[viewer.mode] = {"rects": viewer.hud.rects, "panels": viewer.hud.drawn_panels,
                             "summaries": [s and [s.mean, s.p95] for s in viewer.heat_summaries],
                             "halves": {side: h.technique for side, h in viewer.state.halves.items()}}
    if not script:
        viewer.window.close()

viewer.window.request_draw(frame)
viewer.window.run()
viewer.stop_builds()
print(json.dumps(seen))
"""


def overlap(a, b) -> bool:
    ax, ay, aw, ah = a
    bx, by, bw, bh = b
    return ax < bx + bw and bx < ax + aw and ay < by + bh and by < ay + ah


def test_split_heat_views_show_each_halfs_mean_and_p95_with_every_panel_on_screen(display, adapter, tmp_path):
    env = {**os.environ, "DISPLAY": display, "WGPUVIEWER_CONFIG_DIR": str(tmp_path)}
    result = subprocess.run([sys.executable, "-c", SESSION], capture_output=True, text=True, timeout=300, env=env,
                            cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert not [line for line in result.stderr.splitlines() if line.startswith("ERROR")], result.stderr
    seen = json.loads(result.stdout.strip().splitlines()[-1])
    assert set(seen) == {"cost", "error"}, seen
    for mode, view in seen.items():
        assert view["halves"] == {"A": "pom", "B": "normal"}  # the split opened on pom twice; Tab, 2: B is normal
        assert {"stats", "info", "help", "legend", "split", "status"} <= set(view["panels"]), (mode, view["panels"])
        a, b = view["summaries"]
        assert 0 <= a[0] <= a[1] and 0 <= b[0] <= b[1], (mode, view["summaries"])
        rects = view["rects"]
        for name, (x, y, w, h) in rects.items():
            assert x >= 0 and y >= 0 and x + w <= 640 and y + h <= 400, (mode, name, rects[name])
        bottom = ("split", "legend", "status")  # from the bottom edge up
        assert not [(p, q) for p in bottom for q in bottom if p < q and overlap(rects[p], rects[q])], (mode, rects)
    cost, error = seen["cost"]["summaries"], seen["error"]["summaries"]
    assert cost[1][0] < cost[0][0]  # the normal map fetches no depth: less than pom's layers
    assert error[0][0] < error[1][0]  # and misses the relief pom finds


DRAG = """
import json
from imgui_bundle import imgui
from wgpuviewer.scene import default_scene_path, load_scene
from wgpuviewer.viewer.app import Viewer

viewer = Viewer(load_scene(default_scene_path()), "pom", None, size=(800, 500), scripted=True)
io = imgui.get_io()
steps = {3: "B", 5: "down", 6: (-150, 60), 7: (-250, 100), 8: "up", 10: "B"}  # the mouse drags the title bar
rects, grab = [], []

def frame():
    step = steps.get(len(rects))
    imgui.set_current_context(viewer.hud.imgui.imgui_context)
    if step == "B":
        viewer.press("B")
    elif step == "down":
        x, y, w, h = rects[-1]
        grab.extend((x + 60, y + 8))
        io.add_mouse_pos_event(*grab)
        io.add_mouse_button_event(0, True)
    elif step == "up":
        io.add_mouse_button_event(0, False)
    elif step:
        io.add_mouse_pos_event(grab[0] + step[0], grab[1] + step[1])
    viewer.draw()
    rects.append(viewer.hud.rects["info"])
    if len(rects) == 13:
        viewer.window.close()

viewer.window.request_draw(frame)
viewer.window.run()
print(json.dumps(rects))
"""


def test_the_info_panel_keeps_to_the_right_edge_until_dragged_away(display, adapter, tmp_path):
    env = {**os.environ, "DISPLAY": display, "WGPUVIEWER_CONFIG_DIR": str(tmp_path)}
    result = subprocess.run([sys.executable, "-c", DRAG], capture_output=True, text=True, timeout=300, env=env,
                            cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    rects = json.loads(result.stdout.strip().splitlines()[-1])
    docked = rects[1:7]  # frame 0 is imgui's hidden sizing frame; the split (frame 3) changes its content
    assert all(x + w == pytest.approx(792) and y == pytest.approx(8) for x, y, w, _ in docked), rects
    assert rects[4][3] != rects[2][3]  # the split (a frame later: imgui fits a panel to the last frame's content)
    x0, y0 = rects[4][:2]
    for x, y, _, _ in rects[7:]:  # dragged by (-250, 100), then left there, also when its content changes again
        assert (x, y) == (pytest.approx(x0 - 250), pytest.approx(y0 + 100)), rects
    assert rects[12][3] != rects[9][3]  # joined (frame 10): its size changed, its place did not
