"""The viewer survives what used to end (or freeze) it: a technique whose texture file is bad (the problem in
the HUD, the previous technique stays), long map builds (a worker thread, a progress line, frames keep coming),
an unwritable config folder, an invalid last scene; `--keys` alone ends by itself; the HUD fits 320x240."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import cv2
import numpy as np
import pytest

from tests.relief.scenes import material_scene

SCENE = material_scene(["basic", "normal", "pom"], 'albedo = "good.png"\nnormal = "normal.png"\nheight = "corrupt.png"',
                       position=(0.0, 1.0, 1.6))


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bad-height")
    rng = np.random.default_rng(3)
    cv2.imwrite(str(folder / "good.png"), rng.integers(0, 255, (64, 64, 3), dtype=np.uint8))
    normal = np.zeros((64, 64, 3), np.uint8)
    normal[...] = (255, 128, 128)  # BGR: a flat normal map
    cv2.imwrite(str(folder / "normal.png"), normal)
    data = (folder / "good.png").read_bytes()  # a sound header and end around damaged data
    start, end = data.index(b"IDAT") + 4, data.index(b"IEND") - 8
    (folder / "corrupt.png").write_bytes(data[:start] + bytes(end - start) + data[end:])
    (folder / "s.toml").write_text(SCENE)
    return folder / "s.toml"


SESSION = """
import json, sys, time
from wgpuviewer.scene import load_scene
from wgpuviewer.viewer.app import Viewer

viewer = Viewer(load_scene(sys.argv[1]), "basic", None, size=(320, 240), scripted=True, background=True)
real = viewer.renderer.texture

def slow(material, kind):  # a long map build, so that frames are drawn while it runs
    time.sleep(0.5)
    return real(material, kind)

viewer.renderer.texture = slow
seen = {"frames": 0, "while_building": 0, "progress": 0, "layout": None, "pressed": []}

def frame():
    if seen["frames"] == 0:
        viewer.press("2")  # normal: its normal map file is fine
    elif viewer.state.halves["A"].technique == "normal" and not seen["pressed"]:
        seen["pressed"].append("5")
        viewer.press("5")  # pom: needs the height map, whose data is damaged
    viewer.draw()
    seen["frames"] += 1
    if viewer.builds.current is not None:
        seen["while_building"] += 1
    if "progress" in viewer.hud.drawn_panels:
        seen["progress"] += 1
        seen["layout"] = viewer.hud.rects
    if (seen["pressed"] and viewer.builds.current is None) or seen["frames"] > 3000:
        viewer.window.close()

viewer.window.request_draw(frame)
viewer.window.run()
print(json.dumps({**seen, "technique": viewer.state.halves["A"].technique, "problems": viewer.problems,
                  "problem_shown": "status" in viewer.hud.drawn_panels}))
"""


def run(args, display, tmp_path, timeout=300):
    env = {**os.environ, "DISPLAY": display, "WGPUVIEWER_CONFIG_DIR": str(tmp_path / "config")}
    return subprocess.run(args, capture_output=True, text=True, timeout=timeout, env=env, cwd=tmp_path)


def test_switching_builds_in_the_background_and_a_bad_texture_keeps_the_previous_technique(
        scene, display, adapter, tmp_path):
    result = run([sys.executable, "-c", SESSION, str(scene)], display, tmp_path)
    assert result.returncode == 0, result.stderr
    seen = json.loads(result.stdout.strip().splitlines()[-1])
    assert seen["while_building"] >= 2 and seen["progress"] >= 1, seen  # the window drew on, with the progress line
    assert seen["technique"] == "normal", seen  # pom failed: the previous technique stays
    assert len(seen["problems"]) == 1 and seen["problem_shown"]
    assert seen["problems"][0].startswith(f"{scene}: materials.m.height = 'corrupt.png': cannot decode image")
    assert f"wgpuviewer: error: {seen['problems'][0]}" in result.stderr and "Traceback" not in result.stderr
    # the HUD at 320x240: every panel on screen, none over another
    rects = seen["layout"]
    assert {"stats", "info", "status"} <= set(rects), rects
    for name, (x, y, w, h) in rects.items():
        assert x >= 0 and y >= 0 and x + w <= 320 and y + h <= 240, (name, rects[name])
    names = sorted(rects)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            ax, ay, aw, ah = rects[a]
            bx, by, bw, bh = rects[b]
            assert ax + aw <= bx or bx + bw <= ax or ay + ah <= by or by + bh <= ay, (a, b, rects)


def test_a_scripted_run_with_a_bad_texture_ends_with_one_line_and_exit_2(scene, display, adapter, tmp_path):
    """`--keys` alone makes a scripted run that ends by itself (it used to draw forever); the switch to pom
    fails, the frames go on with basic, and the run reports the problem as its one error line."""
    result = run([sys.executable, "-m", "wgpuviewer", "view", str(scene), "--keys", "H,5", "--size", "160x100"],
                 display, tmp_path, timeout=120)
    assert result.returncode == 2, result.stderr
    errors = [line for line in result.stderr.splitlines() if line.startswith("wgpuviewer: error:")]
    assert len(set(errors)) == 1 and "materials.m.height = 'corrupt.png': cannot decode image" in errors[0]
    assert "Traceback" not in result.stderr


def test_an_unwritable_config_folder_is_a_warning(tmp_path, monkeypatch, capsys):
    from wgpuviewer.viewer.settings import Settings, save_session

    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setenv("WGPUVIEWER_CONFIG_DIR", str(blocker / "wgpuviewer"))
    save_session(Settings())
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"wgpuviewer: warning: settings not saved: {blocker / 'wgpuviewer' / 'settings.toml'} cannot be "
                   "written (Not a directory); set WGPUVIEWER_CONFIG_DIR to a writable folder"]


@pytest.mark.parametrize("last", ["missing.toml", "broken.toml"])
def test_an_invalid_last_scene_falls_back_to_the_default_scene(tmp_path, monkeypatch, capsys, last):
    from wgpuviewer import cli
    from wgpuviewer.scene import default_scene_path
    from wgpuviewer.viewer import app
    from wgpuviewer.viewer.settings import Settings, save_settings

    (tmp_path / "broken.toml").write_text("[camera\n")
    monkeypatch.setenv("WGPUVIEWER_CONFIG_DIR", str(tmp_path / "config"))
    save_settings(Settings(last_scene=str(tmp_path / last), last_technique="steep"))
    monkeypatch.setenv("DISPLAY", ":0")
    opened = {}

    def run_viewer(scene, technique, **kwargs):  # no window: what would be shown is enough
        opened.update(scene=scene, technique=technique, frames=kwargs["frames"])
        return 0

    monkeypatch.setattr(app, "run_viewer", run_viewer)
    assert cli.main(["view"]) == 0
    assert opened["scene"].path == default_scene_path() and opened["technique"] == "pom"
    assert opened["frames"] is None  # interactive
    err = capsys.readouterr().err
    assert f"wgpuviewer: warning: the last scene cannot be opened ({tmp_path / last}" in err
    assert "opening the default scene" in err
