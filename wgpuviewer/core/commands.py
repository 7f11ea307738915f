"""What both command lines (``wgpuviewer`` and ``maptools``) share: preparing the process before any GPU driver
loads, warnings as one line each, argparse errors as one line, option values checked into one-line errors
(sizes, comma-separated lists, the backend), and the exit codes.

Exit codes: 0 success, 1 a check or batch job failed (the commands return it), 2 a user error (``UserError`` or
``InputError``: one line naming the thing and the fix), 3 an internal error (a bug: a one-line summary, and the
traceback saved to a file whose path is printed), 130 interrupted (SIGINT, Ctrl-C), 143 terminated (SIGTERM: it
unwinds like SIGINT, so no temp file is left behind).

This module imports only the standard library at import time, so a CLI can call ``prepare_process`` before
wgpu or OpenCV load.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import shlex
import signal
import sys
import tempfile
import threading
import time
import traceback
from collections.abc import Callable
from pathlib import Path

from .env import check_environment, prepare_driver_environment
from .errors import InputError, UserError

#: Loggers whose warnings the CLIs print as ``PROG: warning: MESSAGE``.
WARNING_LOGGERS = ("wgpuviewer", "maptools")


def prepare_process(prog: str) -> None:
    """Call first in a CLI's ``main``, before any GPU adapter is requested (importing wgpu loads no driver; the
    first adapter request does):

    - on POSIX, a private ``$XDG_RUNTIME_DIR`` when it is unset or invalid (Mesa prints four
      ``error: XDG_RUNTIME_DIR is invalid`` lines otherwise);
    - OpenCV logs errors only (no ``[ WARN:0@...]`` lines; our readers report failures themselves);
    - notes (INFO: what a command chose or found) and warnings of the project's loggers print as one line each on
      stderr, ``PROG: ...`` and ``PROG: warning: ...``.
    """
    prepare_driver_environment()
    os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")
    cv2 = sys.modules.get("cv2")
    if cv2 is not None:  # already imported (in-process callers): the variable is read at import only
        cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
    _warnings_as_lines(prog)


class _WarningLine(logging.Handler):
    def __init__(self, prog: str):
        super().__init__(level=logging.INFO)
        self.prog = prog

    def emit(self, record):
        try:
            # a note (INFO) says what the command chose or found; nothing to act on
            kinds = {logging.INFO: "", logging.WARNING: "warning: "}
            kind = kinds.get(record.levelno, "warning: " if record.levelno < logging.ERROR else "error: ")
            print(f"{self.prog}: {kind}{record.getMessage()}", file=sys.stderr)
        except Exception:  # noqa: BLE001 - a broken stderr must not break the command
            self.handleError(record)


def _warnings_as_lines(prog: str) -> None:
    for name in WARNING_LOGGERS:
        logger = logging.getLogger(name)
        logger.handlers = [h for h in logger.handlers if not isinstance(h, _WarningLine)]
        logger.addHandler(_WarningLine(prog))
        logger.setLevel(logging.INFO)


@contextlib.contextmanager
def terminal_progress(what: str, delay: float = 1.0, unit: str = "map"):
    """Yields ``progress(label, done, total)`` feeding a tqdm bar on stderr: shown once the work has taken
    ``delay`` seconds, only on a terminal, redrawn every half second (its clock runs during one long step, e.g.
    a 3D distance map), gone when the work ends. ``unit`` names what ``done`` counts."""
    from tqdm import tqdm

    state: dict = {}
    stop = threading.Event()

    def tick():
        while not stop.wait(0.5):
            bar = state.get("bar")
            if bar is not None and time.monotonic() - state["start"] >= delay:
                bar.refresh()

    def progress(label: str, done: int, total: int) -> None:
        if "bar" not in state:
            state["start"] = time.monotonic()
            state["bar"] = tqdm(total=total, desc=what, unit=unit, file=sys.stderr, delay=delay, disable=None,
                                leave=False, dynamic_ncols=True)
            threading.Thread(target=tick, daemon=True).start()
        bar = state["bar"]
        bar.total = total
        bar.set_postfix_str(label, refresh=False)
        bar.update(done - bar.n)

    try:
        yield progress
    finally:
        stop.set()
        if "bar" in state:
            state["bar"].close()


def parse_size(text: str, option: str = "--size") -> tuple[int, int]:
    """``WIDTHxHEIGHT`` as (width, height), each 1 to 16384; a UserError naming ``option`` otherwise."""
    try:
        w, h = (int(part) for part in text.lower().split("x"))
    except ValueError:
        raise UserError(f"{option} {text!r}: expected WIDTHxHEIGHT, e.g. 1280x720") from None
    if not (1 <= w <= 16384 and 1 <= h <= 16384):
        raise UserError(f"{option} {text!r}: width and height must be 1 to 16384")
    return w, h


def comma_list(text: str | None, option: str) -> list[str] | None:
    """A comma-separated option value as a list (None when the option was not given)."""
    if text is None:
        return None
    items = [x.strip() for x in text.split(",") if x.strip()]
    if not items:
        raise UserError(f"{option} {text!r}: expected a comma-separated list, e.g. a,b")
    return items


def comma_numbers(text: str | None, option: str, example: str) -> list[float] | None:
    """A comma-separated option value as numbers (None when not given); ``example`` shows a valid value."""
    items = comma_list(text, option)
    if items is None:
        return None
    try:
        return [float(x) for x in items]
    except ValueError:
        raise UserError(f"{option} {text!r}: expected comma-separated numbers, e.g. {example}") from None


def add_backend_option(parser) -> None:
    """``--backend auto|vulkan|metal|dx12|gl`` (imports the GPU module: call it while building a parser)."""
    from .gpu import BACKEND_CHOICES, BACKEND_ENV

    parser.add_argument("--backend", choices=BACKEND_CHOICES,
                        help=f"wgpu backend (default: ${BACKEND_ENV}, else $WGPU_BACKEND_TYPE, else auto: hardware first, "
                             "then software)")


class OneLineParser(argparse.ArgumentParser):
    """argparse with its usage errors as one line, ``PROG: error: MESSAGE; see PROG [COMMAND] --help``, exit 2
    (the line starts like every other error of the program, also for a subcommand's options)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog.split()[0]}: error: {message}; see {self.prog} --help\n")


def command_line(prog: str, argv: list[str]) -> str:
    """The command line ``prog`` with ``argv`` as a shell would take it back (reports and tracebacks record it)."""
    return shlex.join([prog, *argv])


def save_traceback(prog: str, error: BaseException) -> Path | None:
    """The traceback of ``error`` in a new file in the temp dir; None if it cannot be written."""
    text = "".join(traceback.format_exception(error))
    header = f"{command_line(prog, sys.argv[1:])}\n{time.strftime('%Y-%m-%d %H:%M:%S')}, Python {sys.version.split()[0]}\n\n"
    try:
        fd, name = tempfile.mkstemp(prefix=f"{prog}-traceback-", suffix=".txt")
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(header + text)
    except OSError:
        return None
    return Path(name)


def run_command(prog: str, command: Callable[[], int]) -> int:
    """Run a CLI command, after checking the environment variables (``core.env``: every command refuses what any
    refuses), and turn what it raises into the exit codes of the module docstring."""
    with sigterm_unwinds():
        try:
            check_environment()
            return command()
        except (UserError, InputError) as error:
            print(f"{prog}: error: {error}", file=sys.stderr)
            return 2
        except Terminated:
            print(f"{prog}: terminated", file=sys.stderr)
            return 143
        except KeyboardInterrupt:
            print(f"{prog}: interrupted", file=sys.stderr)
            return 130
        except Exception as error:  # noqa: BLE001 - the one place that reports bugs
            if _received:  # an interrupt raised inside a native callback (wgpu's) resurfaces as another error
                print(f"{prog}: {'terminated' if _received[-1] == signal.SIGTERM else 'interrupted'}", file=sys.stderr)
                return 143 if _received[-1] == signal.SIGTERM else 130
            return report_internal_error(prog, error)


class Terminated(KeyboardInterrupt):
    """SIGTERM during a command. A KeyboardInterrupt, so everything that unwinds for Ctrl-C unwinds for it too
    (atomic writes remove their temps, worker pools shut down); ``run_command`` exits 143 for it."""


_received: list[int] = []  # the signals a command's handlers raised for, newest last


def _raise_terminated(signum, frame):
    _received.append(signum)
    raise Terminated


def _raise_interrupted(signum, frame):
    _received.append(signum)
    raise KeyboardInterrupt


@contextlib.contextmanager
def sigterm_unwinds():
    """While inside, SIGTERM raises ``Terminated`` in the main thread instead of ending the process where it stands
    (Python's default, which runs no ``finally`` and leaves temp files behind), SIGINT raises KeyboardInterrupt, and
    both are remembered in ``_received``; the previous handlers come back after. Only the main thread may set
    handlers: from another thread this changes nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    # SIGINT raises KeyboardInterrupt as Python's own handler does, and is remembered: where it lands inside a
    # native callback, the library may turn it into another error (run_command still exits 130 for it)
    previous_int = signal.signal(signal.SIGINT, _raise_interrupted)
    _received.clear()
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL if previous is None else previous)
        signal.signal(signal.SIGINT, signal.default_int_handler if previous_int is None else previous_int)


def report_internal_error(prog: str, error: BaseException) -> int:
    """One line on stderr for a bug, the traceback saved to a file (or printed when that fails); returns 3."""
    summary = f"{type(error).__name__}: {error}".splitlines()[0][:300]
    saved = save_traceback(prog, error)
    if saved is None:
        traceback.print_exception(error, file=sys.stderr)
        where = "the traceback is above"
    else:
        where = f"traceback saved to {saved}"
    print(f"{prog}: internal error: {summary} (a bug; {where}; please report it)", file=sys.stderr)
    return 3
