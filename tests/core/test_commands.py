"""What both CLIs share (wgpuviewer.core.commands): exit codes 2 and 3, one-line argparse errors, the private runtime
dir, warnings as one line. Each mechanism is checked on both CLIs, in-process."""

from __future__ import annotations

import logging
import os
import signal
import stat
import subprocess
import sys

import pytest

from maptools import cli as maptools_cli
from wgpuviewer import cli as wgpuviewer_cli
from wgpuviewer.core import commands
from wgpuviewer.core.errors import InputError, UserError

MAINS = {"wgpuviewer": wgpuviewer_cli.main, "maptools": maptools_cli.main}


@pytest.fixture
def tmp_traceback_dir(tmp_path, monkeypatch):
    monkeypatch.setattr(commands.tempfile, "tempdir", str(tmp_path))
    return tmp_path


def one_error_line(err: str, prog: str, kind: str = "error") -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith(f"{prog}: {kind}:"), err
    assert "Traceback" not in err
    return lines[0]


@pytest.mark.parametrize("prog,argv,fragment", [
    ("wgpuviewer", ["render", "-o", "x.png", "--bogus"], "unrecognized arguments: --bogus"),
    ("wgpuviewer", ["render", "--mode", "nope", "-o", "x.png"], "invalid choice: 'nope'"),
    ("wgpuviewer", ["bench"], "required: --out"),
    ("maptools", ["generate", "normal"], "required: INPUT"),
    ("maptools", ["batch", "in", "-o", "out", "--jobs", "x"], "invalid int value: 'x'"),
    ("maptools", ["frobnicate"], "invalid choice: 'frobnicate'"),
])
def test_argparse_errors_are_one_line_with_the_help_hint(prog, argv, fragment, capsys):
    assert MAINS[prog](argv) == 2
    line = one_error_line(capsys.readouterr().err, prog)
    assert fragment in line and line.endswith("--help"), line


def boom(args):
    raise ZeroDivisionError("division by zero in a bug")


@pytest.mark.parametrize("prog,argv,target", [
    ("wgpuviewer", ["techniques"], (wgpuviewer_cli, "cmd_techniques")),
    ("maptools", ["kinds"], (maptools_cli, "cmd_kinds")),
])
def test_internal_errors_exit_3_with_the_traceback_in_a_file(prog, argv, target, monkeypatch, capsys,
                                                              tmp_traceback_dir):
    module, name = target
    monkeypatch.setattr(module, name, boom)
    assert MAINS[prog](argv) == 3
    line = one_error_line(capsys.readouterr().err, prog, "internal error")
    assert "ZeroDivisionError: division by zero in a bug" in line
    saved = list(tmp_traceback_dir.glob(f"{prog}-traceback-*.txt"))
    assert len(saved) == 1 and str(saved[0]) in line
    text = saved[0].read_text()
    assert "Traceback (most recent call last)" in text and "in boom" in text and "ZeroDivisionError" in text


def test_user_and_input_errors_exit_2_and_interrupts_130(capsys):
    for error in (UserError("x.png: cannot decode"), InputError("probe: uv must have shape (N, 2)")):
        def command(error=error):
            raise error
        assert commands.run_command("wgpuviewer", command) == 2
        assert one_error_line(capsys.readouterr().err, "wgpuviewer") == f"wgpuviewer: error: {error}"

    def interrupted():
        raise KeyboardInterrupt
    assert commands.run_command("maptools", interrupted) == 130


def test_an_unwritable_temp_dir_prints_the_traceback_instead(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(commands.tempfile, "tempdir", str(tmp_path / "missing" / "dir"))
    assert commands.run_command("maptools", lambda: boom(None)) == 3
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err and "the traceback is above" in err.splitlines()[-1]


@pytest.mark.parametrize("value", [None, "", "relative/dir", "/no/such/dir", "wrong-mode", "a-file"])
def test_private_runtime_dir_when_unset_or_invalid(value, monkeypatch, tmp_path):
    if value == "wrong-mode":
        value = str(tmp_path / "open")
        os.mkdir(value, 0o755)
        os.chmod(value, 0o755)
    elif value == "a-file":
        value = str(tmp_path / "file")
        open(value, "w").close()
    if value is None:
        monkeypatch.delenv("XDG_RUNTIME_DIR", raising=False)
    else:
        monkeypatch.setenv("XDG_RUNTIME_DIR", value)
    monkeypatch.setattr(commands.tempfile, "tempdir", str(tmp_path))
    commands.prepare_process("wgpuviewer")
    chosen = os.environ["XDG_RUNTIME_DIR"]
    assert chosen != value and chosen.startswith(str(tmp_path))
    info = os.stat(chosen)
    assert stat.S_IMODE(info.st_mode) == 0o700 and info.st_uid == os.getuid()
    commands.prepare_process("wgpuviewer")  # a second call keeps the (now valid) folder
    assert os.environ["XDG_RUNTIME_DIR"] == chosen


def test_a_valid_runtime_dir_is_kept(monkeypatch, tmp_path):
    good = tmp_path / "run"
    good.mkdir(mode=0o700)
    os.chmod(good, 0o700)
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(good))
    commands.prepare_process("maptools")
    assert os.environ["XDG_RUNTIME_DIR"] == str(good)


def test_a_first_adapter_request_without_runtime_dir_prints_nothing(adapter, tmp_path):
    """The CLIs' entry points prepare the process before wgpu loads a driver: no Mesa runtime-dir lines,
    no OpenCV warnings, the software-adapter notice at most one line."""
    env = {k: v for k, v in os.environ.items() if k != "XDG_RUNTIME_DIR"}
    result = subprocess.run([sys.executable, "-m", "wgpuviewer", "info"], capture_output=True, text=True,
                            timeout=120, env=env, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "XDG_RUNTIME_DIR" not in result.stderr and "WARN" not in result.stderr
    assert len(result.stderr.splitlines()) <= 1, result.stderr


def test_warnings_print_as_one_line(capsys):
    commands.prepare_process("maptools")
    logging.getLogger("wgpuviewer.images").warning("x.npy: 3 NaN/inf texels replaced (--nan-policy zero)")
    commands.prepare_process("maptools")  # preparing twice does not print twice
    logging.getLogger("maptools.cache").warning("second")
    err = capsys.readouterr().err.splitlines()
    assert err == ["maptools: warning: x.npy: 3 NaN/inf texels replaced (--nan-policy zero)",
                   "maptools: warning: second"]


def test_long_builds_show_a_progress_bar_on_a_terminal(monkeypatch):
    import io
    import time

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    out = Terminal()
    monkeypatch.setattr(sys, "stderr", out)
    with commands.terminal_progress("maps for distance", delay=0.2) as progress:
        progress("bricks.distance", 0, 2)
        time.sleep(0.8)  # one long step: the bar appears after the delay and its clock runs
        progress("bumps.distance", 1, 2)
        progress("done", 2, 2)
    text = out.getvalue()
    assert "maps for distance" in text and "bricks.distance" in text and "1/2" in text, text
    quiet = io.StringIO()  # not a terminal: no bar
    monkeypatch.setattr(sys, "stderr", quiet)
    with commands.terminal_progress("maps", delay=0) as progress:
        progress("x", 0, 1)
    assert quiet.getvalue() == ""


def test_prepare_reports_each_texture_it_builds(gpu):
    from wgpuviewer.relief.renderer import Renderer
    from wgpuviewer.scene import default_scene_path, load_scene

    renderer = Renderer(load_scene(default_scene_path()), gpu)
    steps = []
    todo = renderer.missing("normal")
    renderer.prepare("normal", lambda label, done, total: steps.append((label, done, total)))
    assert todo == [(m, k) for m in ("bricks", "bumps") for k in ("albedo", "normal")]
    assert steps == [(f"{m}.{k}", i, 4) for i, (m, k) in enumerate(todo)] + [("done", 4, 4)]
    assert renderer.missing("normal") == [] and renderer.missing("pom") == [("bricks", "depth"), ("bumps", "depth")]


def test_opencv_warnings_are_silenced(tmp_path):
    """Before cv2 is imported (the variable) and after (its log level): no `[ WARN:0@...]` lines."""
    for order in ("prepare, then import", "import, then prepare"):
        steps = ["from wgpuviewer.core.commands import prepare_process", "prepare_process('maptools')", "import cv2"]
        if order.startswith("import"):
            steps = [steps[2], steps[0], steps[1]]
        code = "; ".join([*steps, "cv2.imread('missing.png')", "print('read')"])
        env = {k: v for k, v in os.environ.items() if k != "OPENCV_LOG_LEVEL"}
        result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, env=env,
                                cwd=tmp_path)
        assert result.stdout.strip() == "read", result.stderr
        assert "WARN" not in result.stderr, (order, result.stderr)


def test_the_command_line_is_quoted_as_a_shell_would_need():
    assert commands.command_line("wgpuviewer", ["bench", "--out", "my runs/a", "--suite", "smoke"]) == \
        "wgpuviewer bench --out 'my runs/a' --suite smoke"


@pytest.mark.parametrize("signum,code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_a_library_turned_into_another_error_still_exits_as_the_signal(signum, code, capsys):
    """Where Ctrl-C or SIGTERM lands inside a native callback, the library may swallow the interrupt and raise
    something else (wgpu's device request raised an AssertionError): the exit is still 130/143, not a bug report."""

    def interrupted_inside_a_library():
        try:
            signal.raise_signal(signum)
        except KeyboardInterrupt:
            raise AssertionError("promise still pending") from None
        return 0

    assert commands.run_command("wgpuviewer", interrupted_inside_a_library) == code
    assert "internal error" not in capsys.readouterr().err
    assert commands.run_command("wgpuviewer", lambda: 1 // 0) == 3  # without a signal, a bug is a bug
