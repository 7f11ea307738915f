"""The window: scripted sessions under a (virtual) X display, plus the fly camera."""

from __future__ import annotations

import os
import subprocess
import sys

import cv2
import numpy as np
import pytest

from wgpuviewer.scene import default_scene_path, load_scene
from wgpuviewer.viewer import FlyCamera

# Log records go to stderr as "LEVEL name: message", so ERRORs from wgpu/rendercanvas are visible.
RUNNER = (
    "import logging, sys; logging.basicConfig(level=logging.WARNING, format='%(levelname)s %(name)s: %(message)s');"
    "from wgpuviewer.cli import main; sys.exit(main(sys.argv[1:]))"
)


def scripted(display, tmp_path, name, *args):
    shot = tmp_path / f"{name}.png"
    result = subprocess.run(
        [sys.executable, "-c", RUNNER, "view", "--frames", "4", "--screenshot", str(shot), *args],
        capture_output=True, text=True, timeout=300, env={**os.environ, "DISPLAY": display},
    )
    assert result.returncode == 0, result.stderr
    errors = [line for line in result.stderr.splitlines() if line.startswith("ERROR")]
    assert not errors, errors
    image = cv2.imread(str(shot))
    assert image is not None and image.shape[2] == 3
    return image.astype(np.int16)


def test_keys_switch_techniques(display, tmp_path, adapter):
    basic = scripted(display, tmp_path, "basic", "--keys", "1")
    pom = scripted(display, tmp_path, "pom", "--keys", "5")
    normal = scripted(display, tmp_path, "normal", "--keys", "2")
    cycled = scripted(display, tmp_path, "cycled", "--keys", "1,ArrowRight")
    assert np.abs(basic - pom).mean() > 1.0
    assert np.abs(basic - normal).mean() > 0.1
    assert np.abs(cycled - normal).max() == 0  # Right from technique 1 is technique 2
    assert (basic.std(axis=(0, 1)) > 5).all()  # a real picture, not a blank frame


def test_cost_view_key(display, tmp_path, adapter):
    color = scripted(display, tmp_path, "color", "--keys", "5")
    cost = scripted(display, tmp_path, "cost", "--keys", "5,D")
    assert np.abs(color - cost).mean() > 5


def test_fly_camera_moves_and_resets():
    scene = load_scene(default_scene_path())
    fly = FlyCamera(scene.camera)
    start = fly.camera()
    forward = np.subtract(scene.camera.target, scene.camera.position)
    assert np.allclose(np.subtract(start.target, start.position), forward / np.linalg.norm(forward))
    fly.move(0.0, 0.0, 1.0)
    assert np.allclose(np.subtract(fly.camera().position, start.position), fly.forward)
    fly.look(100.0, 50.0)
    assert not np.allclose(fly.forward, forward / np.linalg.norm(forward))
    fly.look(0.0, -1e6)  # pitch is clamped short of straight up: the view never flips
    assert fly.forward[1] < 1.0 and np.isfinite(fly.forward).all()
    fly.reset()
    assert np.allclose(fly.camera().position, start.position) and np.allclose(fly.camera().target, start.target)
