"""The backend matrix: every backend this machine offers (``wgpuviewer info``'s ``backends:`` line) opens the window,
plays keys and writes its screenshot (``view --frames --keys --screenshot`` under a display), the window shows that
frame, and it is the offscreen render of the same scene (``render``, whose GPU never saw a window); the backends agree
with each other. What cannot work ends in one line and exit 2, never a wgpu-native panic (exit 134): a backend that
cannot present to the window, a backend without an adapter, a window that gives no frame to draw into; a zero-size
window skips its frame.

Runs are tiny (48x32, four frames), every backend's offscreen render shares one process, and all runs start together.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
from types import SimpleNamespace

import cv2
import numpy as np
import pytest
import wgpu

from wgpuviewer.core import window_instance
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import BACKENDS, describe_adapters, offered_backends
from wgpuviewer.viewer import runner
from wgpuviewer.viewer import window as window_module

SIZE, TECHNIQUE = "48x32", "pom"
KEYS = "H,5"  # the HUD hidden (the offscreen render has none), then pom by its key
PANIC = "panicked"  # what wgpu-native prints before it aborts

#: ``view`` in a window, keeping the window's own pixels (X11: XGetImage) after its last frame was presented, in the
#: .npy given first: grabbed again until they are the screenshot's frame (the last present may land a moment later,
#: and until then the window shows an earlier frame), for at most two seconds.
WINDOW_RUNNER = """
import ctypes, sys, time
import cv2, glfw, numpy as np
from wgpuviewer.viewer.window import Window
from wgpuviewer.cli import main

def grab(window):
    if glfw.get_platform() != glfw.PLATFORM_X11:
        return
    shot = cv2.imread(sys.argv[sys.argv.index("--screenshot") + 1])[..., ::-1].astype(np.int16)
    x = ctypes.CDLL("libX11.so.6")
    x.XGetImage.restype = ctypes.c_void_p
    x.XGetImage.argtypes = [ctypes.c_void_p, ctypes.c_ulong] + [ctypes.c_int] * 2 + [ctypes.c_uint] * 2 + [
        ctypes.c_ulong, ctypes.c_int]
    x.XGetPixel.restype, x.XGetPixel.argtypes = ctypes.c_ulong, [ctypes.c_void_p, ctypes.c_int, ctypes.c_int]
    display = glfw.get_x11_display()
    w, h = window.canvas.get_physical_size()
    for _ in range(100):  # a present may land a moment later (Mesa's WSI presents on a thread of its own)
        image = x.XGetImage(int(getattr(display, "value", display)), glfw.get_x11_window(window.canvas._window),
                            0, 0, w, h, 0xFFFFFFFF, 2)
        pixels = np.array([[x.XGetPixel(image, i, j) for i in range(w)] for j in range(h)], np.uint64)
        rgb = np.stack([pixels >> 16, pixels >> 8, pixels], -1).astype(np.uint8)
        if rgb.shape == shot.shape and np.abs(rgb.astype(np.int16) - shot).max() <= 1:
            break
        time.sleep(0.02)
    np.save(sys.argv[1], rgb)

def close(self):  # Window.close, grabbing the window before it goes
    if not self.closed:
        self._start_closing()
        self._loop.call_soon(lambda: (grab(self), self.canvas.close()))

Window.close = close
sys.exit(main(sys.argv[2:]))
"""


def start(args: list[str], env: dict, code: str | None = None) -> subprocess.Popen:
    command = [sys.executable, "-c", code, *args] if code else [sys.executable, "-m", "wgpuviewer", *args]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)


def finish(process: subprocess.Popen) -> SimpleNamespace:
    out, err = process.communicate(timeout=300)
    return SimpleNamespace(returncode=process.returncode, stdout=out, stderr=err)


def rgb(path) -> np.ndarray:
    image = cv2.imread(str(path))
    assert image is not None, path
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB).astype(np.int16)


@pytest.fixture(scope="module")
def offered(adapter) -> list[str]:
    """The backends ``wgpuviewer info`` lists (its ``backends:`` line)."""
    names = offered_backends()
    assert names and set(names) <= set(BACKENDS)
    assert f"backends: {', '.join(names)}" in describe_adapters().splitlines()
    return names


#: ``render`` of every backend given, in one process without a display (its GPU never saw a window): PNGs in the
#: folder given first.
OFFSCREEN_RUNNER = f"""
import sys
from wgpuviewer.cli import main

folder, *backends = sys.argv[1:]
for name in backends:
    args = ["render", "--backend", name, "--technique", "{TECHNIQUE}", "--size", "{SIZE}", "-o"]
    if main([*args, f"{{folder}}/render_{{name}}.png"]):
        sys.exit(1)
"""


@pytest.fixture(scope="module")
def matrix(offered, display, tmp_path_factory):
    """(the offscreen run, {backend: (window run, its screenshot, the window's pixels or None, offscreen picture)}),
    every run started at once."""
    work = tmp_path_factory.mktemp("backends")
    headless = {**os.environ, "DISPLAY": "", "WAYLAND_DISPLAY": ""}
    offscreen = start([str(work), *offered], headless, OFFSCREEN_RUNNER)
    windows = {}
    for name in offered:
        shot, pixels = work / f"window_{name}.png", work / f"pixels_{name}.npy"
        windows[name] = (start([str(pixels), "view", "--backend", name, "--size", SIZE, "--frames", "4", "--keys",
                                KEYS, "--screenshot", str(shot)], {**os.environ, "DISPLAY": display}, WINDOW_RUNNER),
                         shot, pixels)
    runs = {name: (finish(window), shot, np.load(pixels) if pixels.exists() else None, work / f"render_{name}.png")
            for name, (window, shot, pixels) in windows.items()}
    return finish(offscreen), runs


@pytest.mark.parametrize("backend", list(BACKENDS))
def test_every_offered_backend_draws_the_window_like_the_offscreen_render(matrix, offered, backend):
    if backend not in offered:
        pytest.skip(f"this machine offers no {backend} adapter")
    offscreen, runs = matrix
    window, shot, pixels, picture = runs[backend]
    assert window.returncode == 0 and PANIC not in window.stderr, window.stderr
    assert window.stdout.splitlines()[-1] == str(shot)
    assert offscreen.returncode == 0, offscreen.stderr
    drawn, rendered = rgb(shot), rgb(picture)
    assert drawn.shape == (32, 48, 3) and drawn.std() > 5  # a picture, not a blank frame
    assert np.abs(drawn - rendered).max() <= 1  # the window's frame is the offscreen render
    if pixels is not None:  # what the window shows is that frame
        assert np.abs(pixels.astype(np.int16) - drawn).max() <= 1


def test_the_backends_agree_with_each_other(matrix, offered):
    if len(offered) < 2:
        pytest.skip("one backend here")
    offscreen, runs = matrix
    assert offscreen.returncode == 0, offscreen.stderr
    first = rgb(runs[offered[0]][3])
    for name in offered[1:]:
        difference = np.abs(rgb(runs[name][3]) - first)
        assert difference.mean() < 0.5 and (difference > 8).mean() < 0.01, name


#: ``view`` whose GPU starts before the window (a Python program that rendered first): wgpu's instance never learns
#: the window's display. Where the first argument names a backend, its driver is made to offer the window nothing.
REFUSED = """
import sys
from wgpuviewer.core import window_instance
from wgpuviewer.core.gpu import list_adapters
from wgpuviewer.cli import main

real = window_instance.surface_capabilities

def capabilities(context, adapter):
    if adapter.info["backend_type"] == sys.argv[1]:
        return window_instance.SurfaceCaps(0, 0, False)
    return real(context, adapter)

window_instance.surface_capabilities = capabilities
list_adapters()
sys.exit(main(sys.argv[2:]))
"""


def error_lines(result) -> list[str]:
    return [line for line in result.stderr.splitlines() if not line.startswith("notice: ")]


def test_a_backend_that_cannot_present_is_one_line_naming_what_works(offered, display, tmp_path):
    """Where gl is offered, the case ``view --backend gl`` used to abort on (exit 134, a wgpu-native panic in
    wgpuSurfaceConfigure): Mesa's EGL without the window's display cannot present to it. Elsewhere a driver made to
    offer the window nothing."""
    real = "gl" in offered
    name = "gl" if real else offered[0]
    shot = tmp_path / "s.png"
    args = ["view", "--backend", name, "--technique", "basic", "--size", SIZE, "--frames", "2", "--screenshot", str(shot)]
    result = finish(start(["-" if real else BACKENDS[name], *args], {**os.environ, "DISPLAY": display}, REFUSED))
    if real and result.returncode == 0:
        pytest.skip("this driver's gl presents to the window without its display")
    assert result.returncode == 2 and PANIC not in result.stderr, result.stderr
    [line] = error_lines(result)
    hint = " (the GPU started before the window's display was known)" if name == "gl" else ""
    instead = "".join(f"--backend {other}, or " for other in offered if other != name)
    assert line.startswith(f"wgpuviewer: error: the {name} backend cannot present to this window (")
    assert line.endswith(f": its driver offers no surface format for this window{hint}); use {instead}render "
                         f"offscreen (wgpuviewer render --backend {name}, or view without a display)")
    assert not shot.exists()


def test_a_backend_without_an_adapter_is_one_line(offered, display, tmp_path):
    missing = [name for name in BACKENDS if name not in offered]
    if not missing:
        pytest.skip("this machine offers every backend")
    result = finish(start(["view", "--backend", missing[0], "--size", SIZE, "--frames", "2", "--screenshot",
                           str(tmp_path / "s.png")], {**os.environ, "DISPLAY": display}))
    assert result.returncode == 2, result.stderr
    assert error_lines(result) == [
        f"wgpuviewer: error: no GPU adapter found for backend {missing[0]!r} (this machine offers "
        f"{', '.join(offered)}); use --backend {offered[0]} or --backend auto"]


# --- without a GPU ------------------------------------------------------------------------------


def test_a_zero_size_window_skips_its_frame():
    window = window_module.Window.__new__(window_module.Window)  # no toolkit: only what current_texture reads
    window._present = None
    window.canvas = SimpleNamespace(get_physical_size=lambda: (0, 0))
    window.context = SimpleNamespace(get_current_texture=lambda: pytest.fail("asked the surface for a texture"))
    with pytest.raises(wgpu.DrawCancelled, match="zero-sized frame"):
        window.current_texture()


class NoFrames:
    """A window whose every frame is cancelled (a surface lost for good), asked ``asks`` times by its toolkit."""

    def __init__(self, asks: int):
        self.asks, self.closed, self.tries = asks, False, 0

    def request_draw(self, draw):
        self.draw = draw

    def run(self):
        for _ in range(self.asks):
            if self.closed:
                return
            with contextlib.suppress(wgpu.DrawCancelled):
                self.draw()

    def close(self):
        self.closed = True


class LostViewer:
    def __init__(self, window):
        self.window = window

    def draw(self):
        self.window.tries += 1
        raise wgpu.DrawCancelled("Lost (3)")  # what wgpu-py says when reconfiguring did not bring the surface back

    def stop_builds(self):
        pass


def test_a_window_that_gives_no_frame_ends_a_scripted_run_in_one_line(monkeypatch):
    monkeypatch.setattr(runner, "STALL_SECONDS", 0.0)
    window = NoFrames(asks=100)
    with pytest.raises(UserError) as error:
        runner.run(LostViewer(window), frames=3, screenshot=None)
    assert str(error.value) == (
        f"the window gave no frame to draw into (Lost (3)) for {runner.STALL_FRAMES} tries in a row; try another "
        "--backend, or render offscreen (view without a display, or wgpuviewer render)")
    assert window.tries == runner.STALL_FRAMES and window.closed


def test_an_interactive_window_waits_for_frames(monkeypatch):
    monkeypatch.setattr(runner, "STALL_SECONDS", 0.0)
    window = NoFrames(asks=100)
    assert runner.run(LostViewer(window), frames=None) == 0  # a minimised window: frames come back later
    assert window.tries == 100 and not window.closed


def test_the_refusal_names_the_backends_that_can_present(monkeypatch):
    def adapter(kind: str):
        return SimpleNamespace(info={"backend_type": kind}, summary=f"some GPU via {kind}")

    caps = {"Vulkan": window_instance.SurfaceCaps(2, 0x15, True), "OpenGL": window_instance.SurfaceCaps(0, 0, False)}
    monkeypatch.setattr(window_module, "list_adapters", lambda: [adapter("Vulkan"), adapter("OpenGL")])
    monkeypatch.setattr(window_instance, "surface_capabilities", lambda context, a: caps[a.info["backend_type"]])
    assert str(window_module.refusal(adapter("OpenGL"), caps["OpenGL"].problem, None)) == (
        "the gl backend cannot present to this window (some GPU via OpenGL: its driver offers no surface format for "
        "this window); use --backend vulkan, or render offscreen (wgpuviewer render --backend gl, or view without a "
        "display)")
    caps["Vulkan"] = window_instance.SurfaceCaps(2, 0x15, False)
    assert "; use render offscreen (" in str(window_module.refusal(adapter("OpenGL"), "why", None))


def test_the_wgpu_native_hooks_fall_back_instead_of_failing(monkeypatch):
    from wgpu.backends.wgpu_native import _helpers

    assert window_instance.surface_capabilities(object(), object()) is None  # no surface: unknown, no error
    monkeypatch.setattr(window_instance, "_extras", None)
    monkeypatch.setattr(_helpers, "_the_instance", object())  # the GPU started first: too late for the display
    assert window_instance.prepare_instance_for_glfw() is False and not window_instance.display_given()
