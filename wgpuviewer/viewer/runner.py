"""The viewer's run loop, interactive or scripted.

Scripted runs (tests, demos): ``frames`` frames, ``keys`` played one frame each (a pressed key; a fly key held for
a time, ``W:0.5``, takes as many frames as ``keys.parse_script`` gives it), the last frame (HUD included) saved to
``screenshot``; an ERROR logged while drawing makes the run exit 1, an error inside a frame ends it (exit 2 for a
UserError). A key that closes the window (Escape) ends the script: no frame is drawn once the window is closing, even
when the toolkit asks for one more, a run closed before its last frame says so (one line; exit 2 when the screenshot
it was to write is not written), and a map build under way stops before the run returns.

SIGINT (Ctrl-C) and SIGTERM end a run, interactive or scripted, as Escape does, with exit 130 and 143
(``QUIT_SIGNALS``): from the moment the window opens their handler only notes the signal, and the window's loop closes
it (``Window.run``, ``SignalQuit``), never from inside a draw or a toolkit callback (a surface destroyed during a draw
is a wgpu-native panic; a KeyboardInterrupt raised inside a glfw callback is lost).

A window that gives no frame to draw into (wgpu-py cancels the frame: a surface lost for good, a zero-size window)
ends a scripted run after ``STALL_FRAMES`` cancelled frames and ``STALL_SECONDS``, with one line (exit 2), instead of
waiting forever; an interactive run waits (a minimised window).
"""

from __future__ import annotations

import logging
import signal
import sys
import time
from pathlib import Path

import wgpu

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import refuse_directory
from wgpuviewer.relief.output import save_rgb_png

from .keys import parse_script
from .window import SignalQuit

#: The loggers whose ERRORs fail a scripted run.
LOGGERS = ("wgpu", "rendercanvas")
#: A scripted run ends when this many frames in a row were cancelled over at least this long since the last drawn.
STALL_FRAMES = 30
STALL_SECONDS = 10.0
#: The signals that end a run as Escape does, with the exit code and the line each gives (as ``core.commands``).
QUIT_SIGNALS = {signal.SIGINT: (130, "interrupted"), signal.SIGTERM: (143, "terminated")}


def scripted_frames(frames: int | None, screenshot: str | None, keys) -> int | None:
    """How many frames a run draws (None: until the window is closed), after checking the script's arguments
    (``keys``: the ``--keys`` items). Needs no GPU and no display."""
    if frames is not None and frames < 1:
        raise UserError(f"--frames {frames}: expected a positive number of frames")
    steps = parse_script(keys)
    if (screenshot or steps) and frames is None:
        frames = len(steps) + 3  # a screenshot or keys to press imply a scripted run, which ends by itself
    if screenshot:
        refuse_directory(screenshot, "shot.png")
        if not screenshot.lower().endswith(".png"):
            raise UserError(f"--screenshot {screenshot}: expected a .png path")
    return frames


class _ErrorLogCounter(logging.Handler):
    def __init__(self):
        super().__init__(level=logging.ERROR)
        self.count = 0

    def emit(self, record):
        self.count += 1


def _stalled(state: dict) -> bool:
    """Count a cancelled frame; whether the window has given none for STALL_FRAMES tries and STALL_SECONDS."""
    state["cancelled"] += 1
    return state["cancelled"] >= STALL_FRAMES and time.perf_counter() - state["drawn_at"] >= STALL_SECONDS


def run(viewer, frames: int | None = None, screenshot: str | None = None, keys=(), on_end=None) -> int:
    """Draw ``viewer`` in its window until it closes (interactive: ``frames`` None) or for ``frames`` frames,
    playing the ``--keys`` items ``keys``; ``on_end()`` runs once the window is closed, unless a frame's error ends the
    run (before the run's last line, so that a signal's line stays the last)."""
    state = {"frame": 0, "cancelled": 0, "drawn_at": time.perf_counter()}
    pending = parse_script(keys)
    window = viewer.window
    # rendercanvas only logs a failing draw and shows the previous frame: a scripted run must
    # notice, or a broken shader would pass as a green test.
    errors = _ErrorLogCounter()
    for name in LOGGERS:
        logging.getLogger(name).addHandler(errors)

    def frame():
        try:
            if pending and not window.closed:
                step = pending.pop(0)
                if step.seconds:
                    viewer.input.hold(step.key, step.seconds)
                else:
                    viewer.press(step.key)
            if window.closed:  # Escape, or the toolkit asking once more: the surface is going, draw nothing
                raise wgpu.DrawCancelled("the window is closing")
            texture = viewer.draw()
            state["frame"] += 1
            state["cancelled"], state["drawn_at"] = 0, time.perf_counter()
            if frames is not None and state["frame"] >= frames:
                if screenshot:
                    save_rgb_png(Path(screenshot), viewer.read_frame(texture))
                    print(screenshot)
                window.close()
        except wgpu.DrawCancelled as cancelled:
            if frames is not None and not window.closed and _stalled(state):
                state["error"] = UserError(
                    f"the window gave no frame to draw into ({cancelled}) for {state['cancelled']} tries in a row; "
                    "try another --backend, or render offscreen (view without a display, or wgpuviewer render)")
                window.close()
            raise  # the toolkit skips this frame
        except BaseException as error:
            # rendercanvas would log it and call us again forever: stop, and report it after the loop.
            if frames is None and not isinstance(error, UserError):
                raise
            state["error"] = error
            window.close()

    window.request_draw(frame)
    signalled = None
    try:
        window.run()
    except SignalQuit as quit:
        signalled = quit.signum
    finally:
        viewer.stop_builds()
        for name in LOGGERS:
            logging.getLogger(name).removeHandler(errors)
    if on_end is not None and "error" not in state:
        on_end()
    if signalled is not None:
        code, said = QUIT_SIGNALS[signalled]
        print(f"wgpuviewer: {said}", file=sys.stderr)
        return code
    if "error" in state:
        raise state["error"]
    if frames is not None and state["frame"] < frames:
        closed = f"the window was closed after {state['frame']} of {frames} frames"
        if screenshot:  # what the script was for is missing
            raise UserError(f"--screenshot {screenshot} not written: {closed}; drop Escape from --keys, or give "
                            "--frames the number of frames before it")
        print(f"wgpuviewer: {closed}", file=sys.stderr)
    if frames is not None and errors.count:
        print(f"wgpuviewer: error: {errors.count} error(s) logged while drawing", file=sys.stderr)
        return 1
    return 0

