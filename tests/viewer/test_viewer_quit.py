"""Quitting the viewer, each run a subprocess under the virtual display: Escape at the start of a script, in its
middle, and in the A/B split after an in-place distance-map build; Escape and the window manager's close button
while a distance map builds in the background; SIGINT and SIGTERM at random moments (seeded), interactive and
scripted. Every Escape run ends by itself with exit 0 (a crash is exit -11), no ERROR line and no traceback; no frame
is drawn after Escape, a background build stops after the map it is building, and the window's surface is released
with the window (not by the garbage collector at exit); a signal ends a run with 130 or 143, no panic, no temp left.
The scene is tiny (a 32x32 height map) so that each run takes seconds."""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time

import pytest

from tests.relief.scenes import material_scene
from tests.viewer.test_viewer import RUNNER

SCENE = material_scene(["basic", "distance"], 'albedo = [0.8, 0.8, 0.8]\n'
                       'height = { builtin = "bumps", size = [32, 32] }\nheight_scale = 0.05')


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("quit") / "tiny.toml"
    path.write_text(SCENE)
    return path


def run(args, display, tmp_path, code: int = 0):
    env = {**os.environ, "DISPLAY": display, "WGPUVIEWER_CONFIG_DIR": str(tmp_path / "config")}
    result = subprocess.run(args, capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    assert result.returncode == code, (result.returncode, result.stderr)
    errors = [line for line in result.stderr.splitlines() if line.startswith("ERROR")]
    assert not errors and "Traceback" not in result.stderr, result.stderr
    return result


@pytest.mark.parametrize("keys, drawn", [
    ("Escape", 0),  # at the start: Escape is pressed in the first frame, which glfw draws inside its resize callback
    ("1,Escape,9", 1),  # in the middle: 9 is never pressed, and no frame is drawn after Escape
    ("B,Tab,9,Escape", 3),  # in the A/B split, after B's distance map was built in place
])
def test_escape_ends_a_script_with_exit_0(scene, display, adapter, tmp_path, keys, drawn):
    frames = len(keys.split(",")) + 3
    result = run([sys.executable, "-c", RUNNER, "view", str(scene), "--technique", "basic", "--keys", keys,
                  "--size", "160x100"], display, tmp_path)
    assert f"wgpuviewer: the window was closed after {drawn} of {frames} frames\n" in result.stderr


def test_a_screenshot_that_escape_left_unwritten_is_exit_2(scene, display, adapter, tmp_path):
    shot = tmp_path / "shot.png"
    result = run([sys.executable, "-c", RUNNER, "view", str(scene), "--technique", "basic", "--keys", "Escape,2",
                  "--size", "160x100", "--screenshot", str(shot)], display, tmp_path, code=2)
    assert result.stderr.strip().splitlines()[-1] == (
        f"wgpuviewer: error: --screenshot {shot} not written: the window was closed after 0 of 5 frames; drop Escape "
        "from --keys, or give --frames the number of frames before it")
    assert not shot.exists()


#: (signal, exit code, scripted) of the runs a signal ends, each at a random moment from the start (seeded).
SIGNALLED = [(signal.SIGINT, 130, False), (signal.SIGTERM, 143, False), (signal.SIGINT, 130, True),
             (signal.SIGTERM, 143, True)]


#: The CLI, saying on stdout when it is about to run the command (its handlers set from there on).
STARTED = RUNNER.replace("sys.exit(main(", "print('started', flush=True); sys.exit(main(")


@pytest.mark.parametrize(("sig", "code", "scripted"), SIGNALLED)
def test_a_signal_at_a_random_moment_ends_the_viewer_as_escape_does(scene, display, adapter, tmp_path, sig, code,
                                                                    scripted):
    """SIGINT/SIGTERM while the window opens, draws or dispatches glfw's callbacks (a random moment after the
    command starts, seeded), interactive and scripted: exit 130/143 with one line, no wgpu-native panic or abort, no
    traceback, nothing of wgpuviewer's left in the temp folder."""
    temp = tmp_path / "tmp"
    temp.mkdir()
    env = {**os.environ, "DISPLAY": display, "WGPUVIEWER_CONFIG_DIR": str(tmp_path / "config"), "TMPDIR": str(temp)}
    args = [sys.executable, "-c", STARTED, "view", str(scene), "--technique", "basic", "--size", "160x100",
            *(["--frames", "100000"] if scripted else [])]
    process = subprocess.Popen(args, env=env, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert process.stdout.readline() == "started\n"
        time.sleep(random.Random(f"{sig}{scripted}").uniform(0.1, 2.5))
        process.send_signal(sig)
        err = process.communicate(timeout=60)[1]
    finally:
        process.kill()
    assert process.returncode == code, (process.returncode, err)
    assert "panicked" not in err and "Traceback" not in err, err
    assert err.strip().splitlines()[-1] == f"wgpuviewer: {'interrupted' if code == 130 else 'terminated'}", err
    left = [p.name for p in temp.iterdir() if not p.name.startswith("wgpuviewer-runtime-")]  # the driver's, kept
    assert left == [], left


# A background build of the distance technique's maps (normal, depth, distance) that is under way when the window
# closes: the first of them waits for the close, then builds; what comes after it must not be built.
BACKGROUND_BUILD = """
import ctypes, ctypes.util, json, logging, sys, threading, time
import glfw
from wgpuviewer.scene import load_scene
from wgpuviewer.viewer import runner
from wgpuviewer.viewer.app import Viewer

logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
viewer = Viewer(load_scene(sys.argv[1]), "basic", None, size=(160, 100), scripted=True, background=True)
building = threading.Event()
real = viewer.renderer.texture

def texture(material, kind):
    if kind == "normal":
        building.set()
        end = time.perf_counter() + 20
        while not viewer.window.closed and time.perf_counter() < end:
            time.sleep(0.005)
    return real(material, kind)

viewer.renderer.texture = texture


class ClientMessage(ctypes.Structure):
    _fields_ = [("type", ctypes.c_int), ("serial", ctypes.c_ulong), ("send_event", ctypes.c_int),
                ("display", ctypes.c_void_p), ("window", ctypes.c_ulong), ("message_type", ctypes.c_ulong),
                ("format", ctypes.c_int), ("data", ctypes.c_long * 5)]


class XEvent(ctypes.Union):
    _fields_ = [("xclient", ClientMessage), ("pad", ctypes.c_long * 24)]


def window_manager_close():
    # What a window manager sends to the window when its close button is clicked: WM_PROTOCOLS, WM_DELETE_WINDOW.
    x11 = ctypes.CDLL(ctypes.util.find_library("X11"))
    x11.XInternAtom.restype = ctypes.c_ulong
    x11.XInternAtom.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int]
    x11.XSendEvent.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ctypes.c_int, ctypes.c_long, ctypes.c_void_p]
    x11.XFlush.argtypes = [ctypes.c_void_p]
    handle = viewer.window.canvas._window
    display, xid = ctypes.c_void_p(glfw.get_x11_display()), glfw.get_x11_window(handle)
    event = XEvent()
    message = event.xclient
    message.type, message.send_event, message.display, message.window, message.format = 33, 1, display, xid, 32
    message.message_type = x11.XInternAtom(display, b"WM_PROTOCOLS", 0)
    message.data[0] = x11.XInternAtom(display, b"WM_DELETE_WINDOW", 0)
    x11.XSendEvent(display, xid, 0, 0, ctypes.byref(event))
    x11.XFlush(display)


if sys.argv[2] == "escape":  # a script: 9 starts the build, Escape comes in the next frame, once it is under way
    press = viewer.press

    def scripted_press(key):
        if key == "Escape":
            building.wait(20)
        press(key)

    viewer.press = scripted_press
    code = runner.run(viewer, frames=6, keys=["9", "Escape"])
else:  # an interactive run: 9, then the close button once the build is under way
    draw, frames = viewer.draw, []

    def scripted_draw():
        frames.append(len(frames))
        if len(frames) == 1:
            viewer.press("9")
        elif len(frames) == 2:
            building.wait(20)
            window_manager_close()
        elif len(frames) > 1000:  # the close never came: end the run, the test fails on the frame count
            viewer.window.close()
        return draw()

    viewer.draw = scripted_draw
    code = runner.run(viewer)
    print("frames:", len(frames), file=sys.stderr)
if viewer.builds.current is not None:  # a build left running: let it end, to see what it built
    viewer.builds.current.wait(30)
surface = viewer.window.context._wgpu_context  # wgpu's canvas context: its surface must be gone with the window
print(json.dumps({"code": code, "created": viewer.renderer.created, "building": building.is_set(),
                  "threads": [t.name for t in threading.enumerate() if t.name.startswith("maps:")],
                  "surface_released": surface._surface_id is None}))
sys.exit(code)
"""


@pytest.mark.parametrize("how", ["escape", "window-manager"])
def test_closing_during_a_background_map_build_stops_it(scene, display, adapter, tmp_path, how):
    result = run([sys.executable, "-c", BACKGROUND_BUILD, str(scene), how], display, tmp_path)
    seen = json.loads(result.stdout.strip().splitlines()[-1])
    assert seen["code"] == 0 and seen["building"] and seen["threads"] == [] and seen["surface_released"], seen
    assert "texture:m.normal" in seen["created"], seen  # the map under way when the window closed is finished
    assert "texture:m.depth" not in seen["created"] and "texture:m.distance" not in seen["created"], seen
    if how == "window-manager":  # closed by the close button, not by the script's fallback
        assert int(result.stderr.split("frames: ")[1].split()[0]) < 1000, result.stderr
