"""The render scale: the automatic choice from frame times (pure), and a window whose scene is drawn at a fraction of
its size and stretched over it, stepped with the U key, the HUD at full size."""

from __future__ import annotations

import os
import subprocess
import sys

import cv2
import numpy as np
import pytest

from wgpuviewer.viewer.render_scale import CHOICES, SCALES, TARGET_FPS, AutoScale, next_choice, scaled_size


def feed(auto: AutoScale, fps: float) -> list[bool]:
    """One window of frames at ``fps`` (1.2 s: a window ends after 1 s)."""
    return [auto.add(1.0 / fps) for _ in range(int(1.2 * fps) + 1)]


def test_auto_scale_lowers_to_hold_the_target_and_raises_with_margin():
    auto = AutoScale()
    assert any(feed(auto, 3.1))  # 3.1 fps at 1: the largest scale predicted at >= 15 fps
    assert auto.scale == 0.35 and auto.fps == pytest.approx(3.1, rel=0.05) and auto.measured_at == 1.0
    assert not any(feed(AutoScale(0.35), 20.0))  # 0.5 would predict 9.8 fps: stays
    raised = AutoScale(0.35)
    assert any(feed(raised, 50.0)) and raised.scale == 0.5  # 0.5 predicts 24.5 fps, above 15 x 1.4
    assert not any(feed(AutoScale(0.5), TARGET_FPS))  # at the target: stays
    slow = AutoScale(0.25)
    assert not any(feed(slow, 2.0)) and slow.scale == SCALES[-1]  # nothing smaller to take


def test_auto_scale_ignores_outliers_and_short_windows():
    auto = AutoScale()
    assert not auto.add(5.0) and not auto.add(0.0)  # a map build's frame, a zero interval
    assert not any(auto.add(0.1) for _ in range(3)) and auto.fps is None  # under a second
    assert CHOICES[0] == "auto" and next_choice(CHOICES[-1]) == "auto" and next_choice("auto") == "1"
    assert scaled_size((1280, 720), 0.35) == (448, 252) and scaled_size((2, 2), 0.25) == (1, 1)


RUNNER = "import sys; from wgpuviewer.cli import main; sys.exit(main(sys.argv[1:]))"


def run_view(display, tmp_path, name: str, keys: str, settings: str = "") -> tuple[np.ndarray, str]:
    config = tmp_path / name
    config.mkdir()
    if settings:
        (config / "settings.toml").write_text(f"version = 1\n{settings}\n")
    shot = tmp_path / f"{name}.png"
    result = subprocess.run([sys.executable, "-c", RUNNER, "view", "--size", "256x160", "--frames",
                             str(len(keys.split(",")) + 2), "--screenshot", str(shot), "--keys", keys],
                            capture_output=True, text=True, timeout=300, cwd=tmp_path,
                            env={**os.environ, "DISPLAY": display, "WGPUVIEWER_CONFIG_DIR": str(config)})
    assert result.returncode == 0, result.stderr
    return cv2.imread(str(shot)).astype(np.int16), result.stderr


@pytest.mark.requires_gpu
def test_a_scaled_scene_fills_the_window_and_u_steps_the_scale(display, adapter, tmp_path):
    full, _ = run_view(display, tmp_path, "full", "H")  # the default, auto: 1 in a scripted run
    scaled, stderr = run_view(display, tmp_path, "scaled", "H,u,u", 'render_scale = "0.75"')
    assert "render scale: 0.5" in stderr and "render scale: 0.35" in stderr
    assert scaled.shape == full.shape == (160, 256, 3)
    difference = np.abs(scaled - full).mean()
    assert 0.0 < difference < 12.0  # the same view, softer: drawn at 90x56 and stretched
