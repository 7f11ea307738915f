"""The self-shadowing key (L): the state's override cycles the materials' own, off, hard, soft; the draws get it;
in a window it darkens the relief where the lights are hidden. The depth-offset key (Z) cycles its override alike."""

from __future__ import annotations

import os
import subprocess
import sys

import cv2
import numpy as np

from tests.viewer.test_viewer import RUNNER, SMALL
from wgpuviewer.relief.filters import DEFAULT_DERIVATIVES, DEFAULT_FILTER
from wgpuviewer.viewer.keys import PRESSED
from wgpuviewer.viewer.state import ViewerState


def test_l_cycles_the_shadow_override_through_every_mode_and_back():
    state = ViewerState.start(["pom"], "pom", DEFAULT_FILTER, DEFAULT_DERIVATIVES)
    assert state.shadows is None and state.shadows_label == "materials"
    assert PRESSED["l"].action == PRESSED["L"].action == "cycle_shadows"
    seen = [state.cycle_shadows() for _ in range(4)]
    assert seen == ["off", "hard", "soft", None]
    state.toggle_split()
    state.cycle_shadows()
    assert state.shadows == "off"  # one override for both halves


def screenshot(display, tmp_path, keys: str) -> np.ndarray:
    shot = tmp_path / f"{keys.replace(',', '_')}.png"
    (tmp_path / "config").mkdir(exist_ok=True)
    result = subprocess.run(
        [sys.executable, "-c", RUNNER, "view", "--size", SMALL, "--frames", str(len(keys.split(",")) + 2),
         "--screenshot", str(shot), "--keys", keys],
        capture_output=True, text=True, timeout=300, cwd=tmp_path,
        env={**os.environ, "DISPLAY": display, "WGPUVIEWER_CONFIG_DIR": str(tmp_path / "config")},
    )
    assert result.returncode == 0, result.stderr
    assert not [line for line in result.stderr.splitlines() if line.startswith("ERROR")]
    return cv2.cvtColor(cv2.imread(str(shot)), cv2.COLOR_BGR2RGB).astype(np.int16)


def test_the_shadow_key_darkens_the_relief_in_the_window(display, adapter, tmp_path):
    hard = screenshot(display, tmp_path, "H,5,P,L,L")  # materials' own (off) -> off -> hard
    (plain,) = [cv2.cvtColor(cv2.imread(str(p)), cv2.COLOR_BGR2RGB).astype(np.int16)
                for p in tmp_path.glob("wgpuviewer-*-pom-*.png")]  # P: the scene before L
    assert (hard <= plain + 2).all()
    assert ((plain - hard).max(axis=2) > 16).mean() > 0.005


def test_z_cycles_the_depth_offset_override_for_both_halves():
    state = ViewerState.start(["pom"], "pom", DEFAULT_FILTER, DEFAULT_DERIVATIVES)
    assert state.depth_offset is None and state.depth_offset_label == "materials"
    assert PRESSED["z"].action == PRESSED["Z"].action == "cycle_depth_offset"
    seen = [(state.cycle_depth_offset(), state.depth_offset_label) for _ in range(3)]
    assert seen == [(False, "off"), (True, "on"), (None, "materials")]
