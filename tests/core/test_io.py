"""Output paths (wgpuviewer.core.io): a folder where a file is expected, a full disk, a read-only folder, a file
where a folder is expected, an empty path: one line naming the path and the fix, exit 2, nothing left behind, on
every CLI that writes. Stale temps: only abandoned ones of exactly our pattern are removed, never a live writer's
nor a user's file. SIGTERM, like SIGINT, unwinds: a write in progress leaves no temp."""

from __future__ import annotations

import contextlib
import errno
import os
import signal
import subprocess
import sys
import textwrap
import threading

import numpy as np
import pytest

from maptools import cli as maptools_cli
from wgpuviewer import cli as wgpuviewer_cli
from wgpuviewer.core import io
from wgpuviewer.core.errors import UserError


@pytest.fixture
def height_png(tmp_path):
    import cv2

    path = tmp_path / "h.png"
    cv2.imwrite(str(path), (np.arange(64, dtype=np.uint8).reshape(8, 8) * 4))
    return path


def error_line(capsys) -> str:
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip() and not line.startswith("notice:")]
    assert len(err) == 1 and "Traceback" not in err[0], err
    return err[0]


def test_an_existing_folder_as_output_file(tmp_path, height_png, monkeypatch, capsys):
    folder = tmp_path / "existing"
    folder.mkdir()
    monkeypatch.setenv("DISPLAY", ":0")  # `view` gets as far as its checks; no window opens
    runs = [
        (wgpuviewer_cli.main, ["render", "-o", str(folder)]),
        (wgpuviewer_cli.main, ["view", "--screenshot", str(folder)]),
        (maptools_cli.main, ["generate", "normal", str(height_png), "-o", str(folder)]),
    ]
    for main, argv in runs:
        assert main(argv) == 2, argv
        line = error_line(capsys)
        assert f"{folder}: is a directory; give a file name, e.g. {folder}{os.sep}" in line, line
    assert list(folder.iterdir()) == []


def test_a_file_where_a_folder_is_expected(tmp_path, height_png, capsys):
    plain = tmp_path / "plain.txt"
    plain.write_text("x")
    assert wgpuviewer_cli.main(["bench", "--suite", "smoke", "--out", str(plain)]) == 2
    assert f"--out {plain}: exists and is not a folder" in error_line(capsys)
    assert maptools_cli.main(["batch", str(height_png), "-o", str(plain), "--kinds", "normal"]) == 2
    assert f"-o {plain}: exists and is not a folder" in error_line(capsys)
    # a file as a parent folder of an output
    assert maptools_cli.main(["generate", "normal", str(height_png), "-o", str(plain / "n.png")]) == 2
    assert "a part of the path is a file" in error_line(capsys)
    assert plain.read_text() == "x"


def test_a_read_only_output_folder(tmp_path, height_png, monkeypatch, capsys):
    # Tests may run as root, for whom chmod does not make a folder read-only: the OS refusal is simulated.
    real = io.tempfile.mkstemp
    locked = tmp_path / "ro"
    locked.mkdir()

    def mkstemp(*args, dir=None, **kwargs):
        if os.path.abspath(dir) == str(locked):
            raise PermissionError(errno.EACCES, "Permission denied")
        return real(*args, dir=dir, **kwargs)

    monkeypatch.setattr(io.tempfile, "mkstemp", mkstemp)
    assert maptools_cli.main(["batch", str(height_png), "-o", str(locked), "--kinds", "normal"]) == 2
    line = error_line(capsys)
    assert f"-o {locked}: cannot write there (Permission denied); permission denied; choose a folder" in line
    assert maptools_cli.main(["generate", "normal", str(height_png), "-o", str(locked / "n.png")]) == 2
    assert f"{locked / 'n.png'}: cannot write (Permission denied)" in error_line(capsys)
    assert list(locked.iterdir()) == []


@pytest.mark.parametrize("code,fix", [(errno.ENOSPC, "the disk is full"), (errno.EROFS, "the file system is read-only")])
def test_a_full_disk_or_read_only_file_system_mid_write(code, fix, tmp_path, height_png, monkeypatch, capsys):
    out = tmp_path / "n.png"
    out.write_bytes(b"old")

    def fsync(fd):
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(io.os, "fsync", fsync)
    assert maptools_cli.main(["generate", "normal", str(height_png), "-o", str(out)]) == 2
    assert f"{out}: cannot write ({os.strerror(code)}); {fix}" in error_line(capsys)
    from wgpuviewer.relief.output import save_rgb_png

    with pytest.raises(UserError, match=fix):
        save_rgb_png(out, np.zeros((2, 2, 3), np.uint8))
    assert out.read_bytes() == b"old" and sorted(p.name for p in tmp_path.iterdir()) == ["h.png", "n.png"]


def test_other_errors_in_the_body_pass_through_and_leave_nothing(tmp_path):
    with pytest.raises(RuntimeError), io.atomic_open(tmp_path / "x.bin") as f:
        f.write(b"partial")
        raise RuntimeError("a bug")
    assert list(tmp_path.iterdir()) == []


def temps(path):
    return sorted(path.parent.glob(f".{path.name}.*.tmp"))


def test_stale_temps_of_live_writers_survive_cleanup(tmp_path):
    """Two writers of one output (threads here; processes behave alike: the lock is per open file): one's
    cleanup never removes the other's temp; a temp whose writer died (no lock) is removed."""
    out = tmp_path / "map.png"
    abandoned = tmp_path / f".{out.name}.killed_9.tmp"
    abandoned.write_bytes(b"left by a kill -9")
    with writing_in_a_thread(out, b"first", b" writer"):
        live = [t for t in temps(out) if t != abandoned]
        assert len(live) == 1
        assert io.remove_stale_temps(out) == 1  # the abandoned one only
        assert temps(out) == live
    assert out.read_bytes() == b"first writer" and temps(out) == []


@contextlib.contextmanager
def writing_in_a_thread(out, first: bytes, last: bytes = b""):
    """A thread holds ``io.atomic_open(out)`` with ``first`` written while the block runs, then writes ``last``
    and finishes."""
    writing, release = threading.Event(), threading.Event()

    def writer():
        with io.atomic_open(out) as f:
            f.write(first)
            writing.set()
            release.wait(30)
            f.write(last)

    thread = threading.Thread(target=writer)
    thread.start()
    assert writing.wait(30)
    try:
        yield
    finally:
        release.set()
        thread.join(30)


def test_concurrent_batches_into_one_folder_never_fail_each_other(tmp_path, capsys):
    """Issue: one batch's stale-temp cleanup deleted another's in-flight temp (spurious FAILED)."""
    rng = np.random.default_rng(1)
    src = tmp_path / "in"
    src.mkdir()
    for i in range(6):
        np.save(src / f"h{i}.npy", rng.random((48, 48)).astype(np.float32))
    out = tmp_path / "out"
    codes = []

    def batch():
        codes.append(maptools_cli.main(["batch", str(src), "-o", str(out), "--kinds", "normal,maxmip",
                                        "--backend", "cpu", "--force"]))

    threads = [threading.Thread(target=batch) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert codes == [0, 0, 0], capsys.readouterr().out
    assert not [p for p in out.iterdir() if p.name.startswith(".")]


def test_an_output_folder_is_refused_before_anything_is_made(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for empty in ("", " "):
        with pytest.raises(UserError, match=f"^--out {empty!r}: empty; give a folder path$"):
            io.output_dir(empty, "--out")
    dangling = tmp_path / "link"
    dangling.symlink_to(tmp_path / "gone")
    with pytest.raises(UserError, match="link: exists and is not a folder; give a folder path$"):
        io.output_dir(dangling, "--out")
    with pytest.raises(UserError, match="cannot write there .*the name is too long"):
        io.output_dir(tmp_path / "new" / "deeper" / ("x" * 300), "--out")
    assert sorted(os.listdir(tmp_path)) == ["link"]  # the folders made on the way were removed again
    made = io.output_dir(tmp_path / "a" / "b", "--out")
    assert made == tmp_path / "a" / "b" and made.is_dir() and list(made.iterdir()) == []


def test_only_our_abandoned_temps_are_swept(tmp_path):
    """The cleaners take exactly atomic_open's temp names (checked on a live one), unlocked, plain files."""
    out = tmp_path / "plot.png"
    with writing_in_a_thread(out, b"live"):
        (live,) = temps(out)
        assert io.TEMP_NAME.fullmatch(live.name)["target"] == "plot.png"
        fd, stale = io.tempfile.mkstemp(prefix=".plot.png.", suffix=".tmp", dir=tmp_path)  # as a killed writer left it
        os.close(fd)
        users = [".notes.tmp", "draft.tmp", ".plot.png.mine.tmp", ".plot.png.ABCDEFGH.tmp", ".plot.png.abcdefgh.tmpx"]
        for name in users:
            (tmp_path / name).write_text("the user's")
        (tmp_path / ".folder.abcdefgh.tmp").mkdir()
        (tmp_path / ".link.abcdefgh.tmp").symlink_to(tmp_path / "draft.tmp")
        assert io.remove_abandoned_temps(tmp_path) == 1 and not os.path.exists(stale)
        assert io.remove_stale_temps(out) == 0 and live.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [*users, ".folder.abcdefgh.tmp", ".link.abcdefgh.tmp", "plot.png"])


WRITER = textwrap.dedent("""
    import sys, time
    from wgpuviewer.core.commands import run_command
    from wgpuviewer.core.io import atomic_open

    def command():
        with atomic_open(sys.argv[1]) as f:
            f.write(b"partial")
            f.flush()
            print("writing", flush=True)
            time.sleep(60)
        return 0

    sys.exit(run_command("maptools", command))
""")


@pytest.mark.parametrize("signum, code, word", [(signal.SIGTERM, 143, "terminated"), (signal.SIGINT, 130, "interrupted")])
def test_a_signal_mid_write_leaves_no_temp(tmp_path, signum, code, word):
    """SIGTERM (a service manager, `kill`, a CI timeout) is handled as SIGINT: the command unwinds, the temp of
    the write in progress is removed, one line, its own exit code."""
    out = tmp_path / "out" / "map.png"
    proc = subprocess.Popen([sys.executable, "-c", WRITER, str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        assert proc.stdout.readline().strip() == "writing"
        assert len(temps(out)) == 1
        proc.send_signal(signum)
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == code and err.strip() == f"maptools: {word}", err
    assert list(out.parent.iterdir()) == []
