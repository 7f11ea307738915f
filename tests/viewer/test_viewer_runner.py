"""The run loop without a window: a stand-in window that, like a toolkit, may ask for frames after it closed, and
that ends its loop for SIGINT and SIGTERM as the real one does."""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import sys

import pytest
import wgpu

from wgpuviewer.core.errors import UserError
from wgpuviewer.viewer import runner
from wgpuviewer.viewer.window import SignalQuit


class ToolkitWindow:
    """Calls the draw function ``asks`` times, whether or not it closed meanwhile; a cancelled draw is skipped, as
    rendercanvas does. Between frames its loop closes it for a signal noted meanwhile, and raises SignalQuit for it
    after the loop, with the handlers from before it opened back (as ``Window.run``)."""

    def __init__(self, asks: int):
        self.asks, self.closed, self.draw = asks, False, None
        self.quit_signal = None
        self.previous = {sig: signal.signal(sig, self.note) for sig in runner.QUIT_SIGNALS}  # as a Window opens

    def note(self, signum, _frame):
        self.quit_signal = signum

    def request_draw(self, draw):
        self.draw = draw

    def run(self):
        for _ in range(self.asks):
            if self.quit_signal is not None:
                self.close()
            with contextlib.suppress(wgpu.DrawCancelled):
                self.draw()
        for sig, handler in self.previous.items():
            signal.signal(sig, handler)
        if self.quit_signal is not None:
            raise SignalQuit(self.quit_signal)

    def close(self):
        self.closed = True


class FakeViewer:
    def __init__(self, window, fail_at: int | None = None, log_error_at: int | None = None, signal_at=None):
        self.window, self.fail_at, self.log_error_at = window, fail_at, log_error_at
        self.signal_at = signal_at  # (frame, signal): the signal sent to this process while drawing that frame
        self.events: list[str] = []

    def press(self, key):
        self.events.append(f"press {key}")
        if key == "Escape":
            self.window.close()

    def stop_builds(self):
        self.events.append("stop builds")

    def draw(self):
        frame = sum(e == "draw" for e in self.events)
        self.events.append("draw")
        if frame == self.fail_at:
            raise UserError("cannot write the frame")
        if frame == self.log_error_at:
            logging.getLogger(runner.LOGGERS[0]).error("a draw failed")
        if self.signal_at is not None and frame == self.signal_at[0]:
            os.kill(os.getpid(), self.signal_at[1])
            self.events.append("drawn on")  # the handler returned into the draw, which finishes
        return "texture"


def test_a_scripted_run_presses_one_key_per_frame_and_stops_drawing_once_closed():
    window = ToolkitWindow(asks=6)
    viewer = FakeViewer(window)
    assert runner.run(viewer, frames=3, keys=["b", "f"]) == 0
    assert viewer.events == ["press b", "draw", "press f", "draw", "draw", "stop builds"]
    assert window.closed


def test_escape_ends_a_script_before_any_further_draw(capsys, tmp_path):
    window = ToolkitWindow(asks=6)
    viewer = FakeViewer(window)
    assert runner.run(viewer, frames=5, keys=["b", "Escape", "f"]) == 0
    assert viewer.events == ["press b", "draw", "press Escape", "stop builds"]  # f is never pressed
    assert capsys.readouterr().err == "wgpuviewer: the window was closed after 1 of 5 frames\n"


def test_a_screenshot_the_script_closed_before_is_an_error(tmp_path):
    shot = tmp_path / "shot.png"
    with pytest.raises(UserError) as error:
        runner.run(FakeViewer(ToolkitWindow(asks=6)), frames=5, screenshot=str(shot), keys=["b", "Escape", "f"])
    assert str(error.value) == (f"--screenshot {shot} not written: the window was closed after 1 of 5 frames; drop "
                                "Escape from --keys, or give --frames the number of frames before it")
    assert not shot.exists()


@pytest.mark.parametrize(("sig", "code", "said"), [(signal.SIGINT, 130, "interrupted"),
                                                   (signal.SIGTERM, 143, "terminated")])
@pytest.mark.parametrize("frames", [None, 4])
def test_a_signal_during_a_draw_ends_the_run_as_escape_does(capsys, sig, code, said, frames):
    """The signal lands inside a draw: the draw finishes, the loop closes the window, no frame is drawn after; the
    run returns 130/143 with one line, interactive or scripted, the last one (after what ``on_end``, the session's
    save, says), and the handlers from before are back."""
    before = {s: signal.getsignal(s) for s in runner.QUIT_SIGNALS}
    window = ToolkitWindow(asks=8)
    viewer = FakeViewer(window, signal_at=(1, sig))
    assert runner.run(viewer, frames=frames, on_end=lambda: print("settings saved", file=sys.stderr)) == code
    assert viewer.events == ["draw", "draw", "drawn on", "stop builds"] and window.closed
    assert capsys.readouterr().err == f"settings saved\nwgpuviewer: {said}\n"
    assert {s: signal.getsignal(s) for s in runner.QUIT_SIGNALS} == before


def test_an_error_in_a_frame_ends_a_scripted_run_and_is_raised_after_the_loop():
    window = ToolkitWindow(asks=5)
    viewer = FakeViewer(window, fail_at=1)
    ended = []
    with pytest.raises(UserError, match="cannot write"):
        runner.run(viewer, frames=4, on_end=lambda: ended.append(True))
    assert viewer.events == ["draw", "draw", "stop builds"] and window.closed and not ended


@pytest.fixture
def own_logger(monkeypatch):
    """The runner watches a logger of its own here (conftest fails any test that logs an ERROR on wgpu's)."""
    monkeypatch.setattr(runner, "LOGGERS", ("tests.viewer.runner",))


def test_an_error_logged_while_drawing_fails_a_scripted_run(own_logger, capsys):
    viewer = FakeViewer(ToolkitWindow(asks=3), log_error_at=0)
    assert runner.run(viewer, frames=2) == 1
    assert "1 error(s) logged while drawing" in capsys.readouterr().err


def test_an_interactive_run_draws_until_closed(own_logger):
    window = ToolkitWindow(asks=4)
    viewer = FakeViewer(window, log_error_at=0)
    assert runner.run(viewer) == 0  # logged errors fail scripted runs only
    assert viewer.events.count("draw") == 4 and not window.closed and viewer.events[-1] == "stop builds"


def test_the_script_is_checked_before_any_window_opens(tmp_path):
    assert runner.scripted_frames(None, None, ()) is None
    assert runner.scripted_frames(None, None, ["b", "f"]) == 5  # keys imply a run that ends by itself
    assert runner.scripted_frames(None, str(tmp_path / "a.png"), ()) == 3
    assert runner.scripted_frames(7, None, ["b"]) == 7
    with pytest.raises(UserError, match="--frames 0: expected a positive"):
        runner.scripted_frames(0, None, ())
    with pytest.raises(UserError, match="--screenshot .*a.jpg: expected a .png path"):
        runner.scripted_frames(None, str(tmp_path / "a.jpg"), ())
    with pytest.raises(UserError, match="--keys: unknown key 'Nope'"):
        runner.scripted_frames(None, None, ["b", "Nope"])


@pytest.mark.parametrize("keys", ["", ",", ",,"])
def test_keys_that_name_no_key_are_refused_in_one_line(capsys, keys):
    from wgpuviewer import cli

    assert cli.main(["view", "--keys", keys]) == 2
    assert capsys.readouterr().err == (f"wgpuviewer: error: --keys {keys!r}: no keys given; expected comma-separated "
                                       "keys, e.g. 2,3,ArrowRight\n")
