"""The window: scripted sessions under a (virtual) X display (glfw, the adapter wgpu picks).

Each run is a real window replaying keys one per frame; runs are shared between tests (module
cache) and kept small (320x200, a few frames) so the whole file stays within a few seconds per run. The views
the tests compare (techniques, cost and error views, the A/B split, filters) come from one session that presses
P (a scene-only screenshot) at each of them: starting a window process is the slow part.
"""

from __future__ import annotations

import os
import subprocess
import sys

import cv2
import numpy as np
import pytest

from wgpuviewer.techniques import TECHNIQUES

# Log records go to stderr as "LEVEL name: message", so ERRORs from wgpu/rendercanvas are visible.
RUNNER = (
    "import logging, sys; logging.basicConfig(level=logging.WARNING, format='%(levelname)s %(name)s: %(message)s');"
    "from wgpuviewer.cli import main; sys.exit(main(sys.argv[1:]))"
)
SMALL = "320x200"
#: RUNNER whose P screenshots are numbered in the order taken (the viewer's own names carry the technique and the
#: second, so two of one technique within a second would share a file): a session's shots, one per view.
NUMBERED_SHOTS = (
    "import itertools, pathlib; from wgpuviewer.relief.output import save_rgb_png; from wgpuviewer.viewer.app import "
    "Viewer; shots = itertools.count();"
    "Viewer.screenshot = lambda self, texture: save_rgb_png(pathlib.Path.cwd() / f'shot-{next(shots)}.png', "
    "self.read_frame(texture));" + RUNNER
)
#: The views of one session, each the name of the P shot taken at it: from H (no HUD), pom, normal (2, and 1 then
#: Right), pom's cost view (Shift+D) and error view (Shift+E), the A/B split basic | pom, then pom | pom with B's
#: filter cycled twice (trilinear -> aniso -> ewa) and its derivative source once (uv -> displaced).
VIEWS = (("pom", "5"), ("normal", "2"), ("cycled", "1,ArrowRight"), ("cost", "5,D"), ("error", "D,E"),
         ("split", "E,1,B,Tab,5"), ("filters", "Tab,5,Tab,f,f,F"))


class Run:
    def __init__(self, image: np.ndarray, stderr: str, cwd):
        self.image, self.stderr, self.cwd = image, stderr, cwd


def read_rgb(path) -> np.ndarray:
    image = cv2.imread(str(path))
    assert image is not None and image.shape[2] == 3, path
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB).astype(np.int16)


@pytest.fixture(scope="module")
def runs(display, adapter, tmp_path_factory):
    """``runs(name, keys, size=SMALL, settings_text=None)`` -> Run, each distinct run made once; a name of
    ``VIEWS`` -> its shot of the one session that shows them all."""
    cache = {}

    def start(name: str, keys: str, size: str, settings_text: str | None, code: str) -> tuple:
        work = tmp_path_factory.mktemp(name)
        config = work / "config"
        config.mkdir()
        if settings_text is not None:
            (config / "settings.toml").write_text(settings_text)
        shot = work / f"{name}.png"
        result = subprocess.run(
            [sys.executable, "-c", code, "view", "--size", size, "--frames", str(len(keys.split(",")) + 2),
             "--screenshot", str(shot), "--keys", keys],
            capture_output=True, text=True, timeout=300, cwd=work,
            env={**os.environ, "DISPLAY": display, "WGPUVIEWER_CONFIG_DIR": str(config)},
        )
        assert result.returncode == 0, result.stderr
        errors = [line for line in result.stderr.splitlines() if line.startswith("ERROR")]
        assert not errors, errors
        assert not (config / "settings.toml").exists() or settings_text is not None  # scripted: no save
        return work, shot, result.stderr

    def run(name: str, keys: str = "", size: str = SMALL, settings_text: str | None = None) -> Run:
        if name in cache:
            return cache[name]
        if name in dict(VIEWS):
            keys = "H," + ",".join(f"{view_keys},P" for _, view_keys in VIEWS)
            work, _, stderr = start("views", keys, SMALL, None, NUMBERED_SHOTS)
            shots = sorted(work.glob("shot-*.png"), key=lambda p: int(p.stem.split("-")[1]))
            assert len(shots) == len(VIEWS), stderr
            for (view, _), path in zip(VIEWS, shots):
                cache[view] = Run(read_rgb(path), stderr, work)
            return cache[name]
        work, shot, stderr = start(name, keys, size, settings_text, RUNNER)
        cache[name] = Run(read_rgb(shot), stderr, work)
        return cache[name]

    return run


def test_keys_switch_techniques(runs):
    basic = runs("basic", "H,1,P").image  # H hides the HUD: pure scene pixels
    pom = runs("pom").image
    normal = runs("normal").image
    cycled = runs("cycled").image  # 1 then Right
    assert np.abs(basic - pom).mean() > 1.0
    assert np.abs(basic - normal).mean() > 0.1
    assert np.abs(cycled - normal).max() == 0  # Right from technique 1 is technique 2
    assert (basic.std(axis=(0, 1)) > 5).all()  # a real picture, not a blank frame


def test_screenshot_key_writes_png(runs):
    run = runs("basic", "H,1,P")
    shots = list(run.cwd.glob("wgpuviewer-*-basic-*.png"))
    assert len(shots) == 1, run.stderr
    assert f"screenshot: {shots[0]}" in run.stderr
    image = cv2.imread(str(shots[0]))
    assert image.shape[:2] == (200, 320) and image.std() > 5


def test_cost_and_error_views(runs):
    pom = runs("pom").image
    cost = runs("cost").image  # pom, Shift+D
    error = runs("error").image  # pom, Shift+E
    assert np.abs(pom - cost).mean() > 5
    assert np.abs(pom - error).mean() > 5
    # Heat colours: red >= green >= blue wherever the error map painted something.
    painted = np.abs(error - pom).sum(axis=2) > 30
    assert painted.mean() > 0.2
    r, g, b = (error[painted][:, i] for i in range(3))
    assert (r >= g - 2).mean() > 0.95 and (g >= b - 2).mean() > 0.95


def test_hud_appears_and_h_hides_it_and_corrupt_settings_are_survived(runs):
    hidden = runs("pom").image
    # The HUD run also starts from a corrupt settings file: defaults, a warning, no crash.
    hud = runs("hud", "5", settings_text="width = = [broken\n")
    assert "corrupt" in hud.stderr and "using default settings" in hud.stderr
    changed = np.abs(hud.image - hidden).sum(axis=2) > 30
    assert changed[10:50, 10:130].mean() > 0.03  # the statistics panel's text, top left
    assert changed[10:25, -100:].mean() > 0.2  # the technique panel's title bar, top right (compact HUD)
    assert changed[170:, :140].mean() < 0.2  # the scene itself shows below the panels


def test_split_view_shows_two_techniques(runs):
    basic = runs("basic", "H,1,P").image
    pom = runs("pom").image
    split = runs("split").image  # A = basic, Tab makes B active, 5 = pom on the right
    left, right = slice(0, 150), slice(170, 320)
    assert np.abs(split[:, left] - basic[:, left]).mean() < 0.5
    assert np.abs(split[:, right] - pom[:, right]).mean() < 0.5
    assert np.abs(split[:, right] - basic[:, right]).mean() > 1.0


def test_filter_key_changes_the_active_half_only(runs):
    """F cycles the active half's texture filter, Shift+F its derivative source: B = pom with EWA on the displaced
    uv (trilinear -> aniso -> ewa), A stays pom with trilinear."""
    pom = runs("pom").image
    split = runs("filters")  # A = pom; B = pom, f, f, F
    left, right = slice(0, 150), slice(170, 320)
    assert np.abs(split.image[:, left] - pom[:, left]).mean() < 0.5
    assert np.abs(split.image[:, right] - pom[:, right]).mean() > 0.3


def test_interactive_session_saves_its_settings(display, adapter, tmp_path):
    code = (
        "import sys; from wgpuviewer.viewer.app import run_viewer; from wgpuviewer.scene import *;"
        "sys.exit(run_viewer(load_scene(default_scene_path()), 'steep', frames=3, keys=['H', 'O'],"
        " size=(320, 200), save=True))"
    )
    env = {**os.environ, "DISPLAY": display, "WGPUVIEWER_CONFIG_DIR": str(tmp_path)}
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, env=env)
    assert result.returncode == 0, result.stderr
    from wgpuviewer.scene import default_scene_path
    from wgpuviewer.viewer.settings import load_settings

    saved, warnings = load_settings(tmp_path / "settings.toml")
    assert warnings == []
    assert (saved.width, saved.height) == (320, 200)
    assert saved.camera_mode == "orbit" and saved.show_hud is False
    assert saved.last_technique == "steep" and saved.last_scene == str(default_scene_path())


BROKEN_RELOAD = """
import sys
from wgpuviewer.core import wgsl
from wgpuviewer.scene import default_scene_path, load_scene
from wgpuviewer.techniques import TECHNIQUES
from wgpuviewer.viewer.app import run_viewer

good, reads = wgsl.read_wgsl, []

def edited(name):  # pom.wgsl reads fine once (the first build), then is "edited" into an error
    if name != TECHNIQUES["pom"].wgsl_file:
        return good(name)
    reads.append(name)
    return good(name) + ("\\nfn oops() -> f32 { return 1.0 +; }\\n" if len(reads) > 1 else "")

wgsl.read_wgsl = edited
sys.exit(run_viewer(load_scene(default_scene_path()), "basic", frames=4, keys=["5", "F5"], size=(320, 200),
                    screenshot=sys.argv[1]))
"""


def test_broken_shader_edit_keeps_the_window_drawing(display, adapter, tmp_path):
    # The window's reload path: F5 rebuilds pom's pipeline from a broken source; the old one keeps drawing.
    shot = tmp_path / "broken.png"
    env = {**os.environ, "DISPLAY": display, "WGPUVIEWER_CONFIG_DIR": str(tmp_path)}
    result = subprocess.run([sys.executable, "-c", BROKEN_RELOAD, str(shot)], capture_output=True, text=True,
                            timeout=300, env=env)
    assert result.returncode == 0, result.stderr
    pom = TECHNIQUES["pom"].wgsl_file
    lines = [line for line in result.stderr.splitlines() if line.startswith(f"shader error: {pom}:")]
    assert len(lines) == 1 and "expected" in lines[0], result.stderr
    image = cv2.imread(str(shot))
    assert image is not None and image.std() > 5


def test_missing_qt_is_a_clear_error(monkeypatch, tmp_path, capsys):
    import importlib.util

    if any(importlib.util.find_spec(qt) for qt in ("PySide6", "PyQt6", "PySide2", "PyQt5")):
        pytest.skip("a Qt binding is installed")
    from wgpuviewer.cli import main

    monkeypatch.setenv("DISPLAY", ":0")  # no window is opened: the toolkit check comes first
    monkeypatch.setenv("WGPUVIEWER_CONFIG_DIR", str(tmp_path))
    assert main(["view", "--gui", "qt", "--frames", "2"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("wgpuviewer: error: --gui qt:") and "pip install PySide6" in err


def test_scripted_run_errors_end_the_run(display, tmp_path, adapter):
    """A failure inside a frame (here: an unwritable screenshot path) ends a scripted run with one line
    and exit 2 instead of redrawing forever; unknown keys are refused up front."""
    env = {**os.environ, "DISPLAY": display, "WGPUVIEWER_CONFIG_DIR": str(tmp_path)}
    base = [sys.executable, "-m", "wgpuviewer", "view", "--size", "160x100", "--frames", "2"]
    result = subprocess.run([*base, "--screenshot", "/proc/no/such/shot.png"], capture_output=True, text=True,
                            timeout=120, env=env)
    assert result.returncode == 2 and "cannot write" in result.stderr and "Traceback" not in result.stderr
    result = subprocess.run([*base, "--keys", "Nope"], capture_output=True, text=True, timeout=120, env=env)
    assert result.returncode == 2 and "--keys: unknown key 'Nope'" in result.stderr


def test_vsync_and_fullscreen_go_through_the_window_adapter(runs):
    """V and F11 reach the surface and the toolkit (rendercanvas hooks live in viewer.window): each says what it did,
    nothing reports a hook that moved, and the frames go on."""
    run = runs("window_hooks", "V,F11,F11,V")
    lines = run.stderr.splitlines()
    assert [line for line in lines if line.startswith("vsync ")] == ["vsync on", "vsync off"]
    assert not [line for line in lines if line.startswith(("vsync:", "fullscreen:"))], run.stderr
    assert run.image.std() > 0  # the scene, not a blank frame
