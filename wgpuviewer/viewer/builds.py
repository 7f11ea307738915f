"""Building what a technique needs (texture files, derived maps: a 3D distance map takes a minute) on a worker
thread while the window keeps drawing the technique shown; the HUD shows the progress line, and a problem (a bad
texture file) comes back as a message instead of ending the viewer. When the window closes, the build under way
stops after the map it is building and the viewer waits for it: no thread uses the device while the interpreter
exits.
"""

from __future__ import annotations

import sys
import threading
import time

from wgpuviewer.core.commands import save_traceback
from wgpuviewer.core.errors import InputError, UserError


def progress_line(technique: str, label: str, done: int, total: int, elapsed: float) -> str:
    """The HUD's build line: the map under way, the count of maps done, the time so far and, once a map is done, the
    time left at the pace so far (maps differ in cost: an estimate), e.g.
    ``building distance: bricks.distance (map 3/8), 12 s, about 20 s left``."""
    if not total or done >= total:  # nothing reported yet, or every map built: the last step is under way
        return f"building {technique}: finishing, {elapsed:.0f} s"
    line = f"building {technique}: {label} (map {done + 1}/{total}), {elapsed:.0f} s"
    if done:
        line += f", about {elapsed / done * (total - done):.0f} s left"
    return line


class _Cancelled(Exception):
    """Raised in the worker at the next map once ``MapBuild.cancel`` was called."""


class MapBuild:
    """``renderer.prepare(technique)`` on a daemon thread for A/B side ``side``; poll ``finished``."""

    def __init__(self, renderer, technique: str, side: str):
        self.technique, self.side = technique, side
        self.step = ("", 0, 0)  # the last progress report: (label, maps done, maps in all), set in one assignment
        self.error: str | None = None
        self.started = time.perf_counter()
        self._cancel = threading.Event()
        self._thread = threading.Thread(target=self._run, args=(renderer,), name=f"maps:{technique}", daemon=True)
        self._thread.start()

    def _run(self, renderer) -> None:
        try:
            renderer.prepare(self.technique, self._progress)
        except _Cancelled:
            pass
        except (UserError, InputError) as error:
            self.error = str(error)
        except Exception as error:  # noqa: BLE001 - a bug must not end the viewer; it is reported with its trace
            saved = save_traceback("wgpuviewer", error)
            self.error = (f"internal error building {self.technique}: {type(error).__name__}: {error} "
                          f"(a bug; traceback {f'saved to {saved}' if saved else 'not saved'})")

    def _progress(self, label: str, done: int, total: int) -> None:
        # prepare reports each map before it builds it: the one place a build can stop between maps
        if self._cancel.is_set():
            raise _Cancelled
        self.step = (label, done, total)

    def cancel(self) -> None:
        """Stop before the next map (the one being built is finished: a GPU dispatch cannot be interrupted)."""
        self._cancel.set()

    @property
    def finished(self) -> bool:
        return not self._thread.is_alive()

    def wait(self, timeout: float | None = None) -> bool:
        self._thread.join(timeout)
        return self.finished

    def line(self) -> str:
        """The HUD's progress line (``progress_line``)."""
        label, done, total = self.step
        return progress_line(self.technique, label, done, total, time.perf_counter() - self.started)


class Builds:
    """The map-build orchestration of the two A/B sides: what each side asked for last (``wanted``) and the one
    ``MapBuild`` under way (``current``). A technique whose maps are ready is shown at once; otherwise it is built
    in the background (or in place, ``background`` False: scripted runs) and shown when done, if still wanted."""

    def __init__(self, renderer, background: bool, *, show, problem, shown):
        """``show(side, name)`` shows a technique, ``problem(text)`` reports one, ``shown(side)`` is the technique
        a side shows now."""
        self.renderer, self.background = renderer, background
        self._show, self._problem, self._shown = show, problem, shown
        self.current: MapBuild | None = None
        self.wanted: dict[str, str] = {}

    def ready(self, name: str) -> bool:
        return not self.renderer.missing(name)

    def request(self, side: str, name: str) -> None:
        self.wanted[side] = name
        if self.ready(name):
            self._show(side, name)
        elif not self.background:
            try:
                self.renderer.prepare(name)
            except (UserError, InputError) as error:
                self._problem(str(error))
                return
            self._show(side, name)
        elif self.current is None:
            self.current = MapBuild(self.renderer, name, side)

    def poll(self) -> None:
        """A finished build: show its technique where it is still wanted, or report its problem; then build
        what was asked for meanwhile."""
        build = self.current
        if build is None or not build.finished:
            return
        self.current = None
        if build.error:
            self._problem(build.error)
            if self.wanted.get(build.side) == build.technique:  # not asked for again until a key asks
                self.wanted[build.side] = self._shown(build.side)
        elif self.wanted.get(build.side) == build.technique:
            self._show(build.side, build.technique)
        for side, name in self.wanted.items():
            if self.current is None and not self.ready(name):
                self.current = MapBuild(self.renderer, name, side)

    def cancel(self) -> None:
        """The window is closing: the build under way stops after the map it is building."""
        if self.current is not None:
            self.current.cancel()

    def stop(self) -> None:
        """The window has closed: cancel the build under way and wait for it (nothing it built is shown), so that
        no thread uses the device while the interpreter exits."""
        build, self.current = self.current, None
        if build is None:
            return
        build.cancel()
        if not build.wait(1.0):
            print(f"wgpuviewer: the window has closed; the {build.technique} build stops once "
                  f"{build.step[0] or 'its current map'} is built", file=sys.stderr)
            build.wait()
