"""``view`` without a display: ``--screenshot PATH`` writes PATH (an offscreen render of the scene the window would
show), and ``--keys`` is checked before the scene loads, the GPU starts or a display is looked for: a bad script is
one line and exit 2 with or without a display, a good one cannot be played without a window (one line, exit 2)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from wgpuviewer import cli


@pytest.fixture
def headless(monkeypatch, tmp_path):
    monkeypatch.setenv("DISPLAY", "")
    monkeypatch.setenv("WAYLAND_DISPLAY", "")
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.fixture
def nothing_starts(monkeypatch):
    """A scene load, a GPU start or a window fails the test (exit 3 instead of the expected 2)."""

    def started(*args, **kwargs):
        raise AssertionError("started")

    monkeypatch.setattr(cli, "load_scene_arg", started)
    monkeypatch.setattr("wgpuviewer.core.gpu.get_gpu", started)
    monkeypatch.setattr("wgpuviewer.viewer.app.run_viewer", started)


def error_line(capsys) -> str:
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in captured.err, captured.err
    return lines[0]


def test_screenshot_without_a_display_writes_the_path(headless, capsys, adapter):
    shot = headless / "shots" / "s.png"
    assert cli.main(["view", "--technique", "pom", "--size", "48x32", "--frames", "2", "--screenshot", str(shot)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == (f"no display found (DISPLAY/WAYLAND_DISPLAY unset): writing {shot} as an offscreen render of "
                      "the scene (no HUD)")
    assert out[-1] == str(shot)
    assert not (headless / "out").exists()  # nothing written anywhere else
    # the same picture as `render` of the same scene, technique and size
    assert cli.main(["render", "--technique", "pom", "--size", "48x32", "-o", str(headless / "r.png")]) == 0
    picture = cv2.imread(str(shot))
    assert picture.shape == (32, 48, 3) and picture.std() > 5
    assert np.array_equal(picture, cv2.imread(str(headless / "r.png")))


@pytest.mark.parametrize("display", ["", ":0"])
@pytest.mark.parametrize("keys, message", [
    ("2,Nope", "--keys: unknown key 'Nope'"),
    ("W:half", "--keys: 'W:half': expected W:SECONDS"),
    ("w", "--keys: 'w' is a fly key, held for a time"),
])
def test_a_bad_script_is_refused_before_anything_starts(monkeypatch, headless, nothing_starts, capsys, display, keys,
                                                        message):
    monkeypatch.setenv("DISPLAY", display)
    assert cli.main(["view", "--keys", keys, "--screenshot", str(headless / "s.png")]) == 2
    assert error_line(capsys).startswith(f"wgpuviewer: error: {message}")
    assert list(headless.iterdir()) == []


def test_keys_without_a_display_are_refused_in_one_line(headless, nothing_starts, capsys):
    assert cli.main(["view", "--keys", "2,W:0.5", "--screenshot", str(headless / "s.png")]) == 2
    assert error_line(capsys) == (
        "wgpuviewer: error: --keys 2,W:0.5: no display (DISPLAY/WAYLAND_DISPLAY unset) to play them in; run under one "
        "(e.g. xvfb-run -a wgpuviewer view ...), or drop --keys for an offscreen --screenshot")
    assert list(headless.iterdir()) == []


def test_a_bad_screenshot_path_is_refused_before_anything_starts(headless, nothing_starts, capsys):
    assert cli.main(["view", "--screenshot", str(headless / "s.jpg")]) == 2
    assert error_line(capsys) == f"wgpuviewer: error: --screenshot {headless / 's.jpg'}: expected a .png path"
