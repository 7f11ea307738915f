"""The fly keys in scripts (``--keys W:0.5``): parsing, the frames a hold takes, the camera motion they make
whatever a frame takes, and a real window moving its camera the same for one hold or two halves of it."""

from __future__ import annotations

import os
import subprocess
import sys

import cv2
import numpy as np
import pytest

from tests.viewer.test_viewer import RUNNER
from wgpuviewer.core.errors import UserError
from wgpuviewer.scene import Camera
from wgpuviewer.viewer import runner
from wgpuviewer.viewer.cameras import FlyCamera
from wgpuviewer.viewer.input import Input
from wgpuviewer.viewer.keys import ScriptStep, parse_script


def test_a_hold_is_as_many_frames_as_its_seconds_take_at_the_script_frame_time():
    steps = parse_script(["2", "W:0.5", "ArrowRight", "d:0.05", "E"])
    assert steps[0] == ScriptStep("2") and steps[16] == ScriptStep("ArrowRight") and steps[-1] == ScriptStep("E")
    held = steps[1:16]
    assert {s.key for s in held} == {"w"} and sum(s.seconds for s in held) == pytest.approx(0.5)
    strafe = steps[17:19]  # 0.05 s: two frames of 0.025 s (either case is the fly key when held)
    assert [s.key for s in strafe] == ["d", "d"] and [s.seconds for s in strafe] == pytest.approx([0.025, 0.025])
    assert len(parse_script(["q:0.001"])) == 1 and len(parse_script(["Q:60"])) == 1800
    assert runner.scripted_frames(None, None, ["W:0.5"]) == 15 + 3  # the run lasts as long as its script


@pytest.mark.parametrize("item, message", [
    ("Nope", "--keys: unknown key 'Nope'; known: 0, 1,"),
    ("w", "--keys: 'w' is a fly key, held for a time: give the seconds, e.g. w:0.5"),
    ("W", "--keys: 'W' is a fly key, held for a time: give the seconds, e.g. W:0.5"),
    ("B:1", "--keys: 'B:1': only the fly keys W A S D Q E are held for a time; a pressed key is given alone"),
    ("Nope:1", "--keys: 'Nope:1': only the fly keys W A S D Q E are held"),
    ("W:0", "--keys: 'W:0': expected W:SECONDS with SECONDS in (0, 60], e.g. W:0.5"),
    ("W:61", "--keys: 'W:61': expected W:SECONDS with SECONDS in (0, 60]"),
    ("a:nan", "--keys: 'a:nan': expected a:SECONDS"),
    ("W:", "--keys: 'W:': expected W:SECONDS"),
    ("W:half", "--keys: 'W:half': expected W:SECONDS"),
])
def test_bad_script_items_are_one_line_naming_the_fix(item, message):
    with pytest.raises(UserError) as error:
        runner.scripted_frames(None, None, ["1", item])
    assert str(error.value).startswith(message) and "\n" not in str(error.value)


def test_the_pressed_keys_stay_what_they_were():
    """Held or pressed is told by the duration: D alone is the cost view, d:0.5 strafes; E alone the error view."""
    assert [s.key for s in parse_script(["D", "E", "b"])] == ["D", "E", "b"]
    assert all(s.seconds == 0 for s in parse_script(["D", "E", "b"]))


class Window:
    closed = False

    def on(self, handler, *kinds):
        pass


class Viewer:
    """What Input needs of the viewer, and a record of what the run loop asked of it."""

    def __init__(self, camera_mode="fly"):
        self.window = Window()
        self.camera_mode = camera_mode
        self.fly = FlyCamera(Camera(position=(0.0, 1.0, 3.0), target=(0.0, 1.0, 0.0)))
        self.move_speed = 2.0
        self.messages = []
        self.input = Input(self)

    def message(self, text):
        self.messages.append(text)


def test_a_scripted_hold_moves_by_its_seconds_whatever_the_frame_took():
    viewer = Viewer()
    viewer.input.hold("w", 0.25)
    viewer.input.hold("d", 0.5)
    viewer.input.fly(dt=0.1)  # the frame's real time plays no part for scripted holds
    assert viewer.fly.position == pytest.approx((2.0 * 0.5, 1.0, 3.0 - 2.0 * 0.25))
    viewer.input.fly(dt=0.1)  # a hold lasts one frame
    assert viewer.fly.position == pytest.approx((1.0, 1.0, 2.5))
    viewer.input.held.add("q")  # a key held in the window still moves by the frame's time
    viewer.input.fly(dt=0.1)
    assert viewer.fly.position == pytest.approx((1.0, 1.0 - 0.2, 2.5))


def test_a_scripted_hold_in_the_orbit_camera_says_once_that_it_moves_nothing():
    viewer = Viewer(camera_mode="orbit")
    for _ in range(3):
        viewer.input.hold("w", 0.1)
        viewer.input.fly(dt=0.1)
    assert viewer.fly.position == pytest.approx((0.0, 1.0, 3.0))
    assert viewer.messages == ["--keys W: the fly keys move the fly camera; the orbit camera is on (O switches)"]


class ScriptWindow(Window):
    def request_draw(self, draw):
        self.draw = draw

    def run(self):
        while not self.closed:
            self.draw()

    def close(self):
        self.closed = True


class ScriptViewer(Viewer):
    def __init__(self):
        super().__init__()
        self.window = ScriptWindow()
        self.events = []
        hold = self.input.hold
        self.input.hold = lambda key, seconds: (self.events.append(f"hold {key} {seconds:.4f}"), hold(key, seconds))

    def press(self, key):
        self.events.append(f"press {key}")

    def draw(self):
        self.input.fly(0.1)
        self.events.append("draw")

    def stop_builds(self):
        pass


def test_the_run_loop_holds_fly_keys_and_presses_the_others():
    viewer = ScriptViewer()
    assert runner.run(viewer, frames=5, keys=["O", "s:0.1", "1"]) == 0
    assert viewer.events == ["press O", "draw", "hold s 0.0333", "draw", "hold s 0.0333", "draw",
                             "hold s 0.0333", "draw", "press 1", "draw"]
    assert viewer.fly.position == pytest.approx((0.0, 1.0, 3.0 + 2.0 * 0.1))


def test_a_hold_moves_the_window_camera_the_same_in_one_piece_or_two(display, adapter, tmp_path):
    """A real window: W:0.4 and w:0.2,W:0.2 end at the same camera (the same pixels), which is not the start (the
    second run's P shot, before its holds)."""

    def shot(keys: str, cwd) -> np.ndarray:
        cwd.mkdir()
        out = cwd / "end.png"
        env = {**os.environ, "DISPLAY": display, "WGPUVIEWER_CONFIG_DIR": str(tmp_path / "config")}
        result = subprocess.run([sys.executable, "-c", RUNNER, "view", "--technique", "basic", "--size", "160x100",
                                 "--keys", keys, "--screenshot", str(out)],
                                capture_output=True, text=True, timeout=300, env=env, cwd=cwd)
        assert result.returncode == 0, result.stderr
        assert not [line for line in result.stderr.splitlines() if line.startswith("ERROR")], result.stderr
        return cv2.imread(str(out)).astype(int)

    whole, halves = shot("H,W:0.4", tmp_path / "whole"), shot("H,P,w:0.2,W:0.2", tmp_path / "halves")
    (start,) = [cv2.imread(str(p)).astype(int) for p in (tmp_path / "halves").glob("wgpuviewer-*-basic-*.png")]
    assert np.abs(whole - start).mean() > 1.0  # the camera moved
    assert np.abs(whole - halves).max() == 0
