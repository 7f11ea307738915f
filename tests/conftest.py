"""The one conftest: one adapter check per session (in a subprocess, with a timeout) behind the ``adapter`` and
``gpu`` fixtures and the ``requires_gpu`` marker, failing on ERROR logs from wgpu/rendercanvas, a virtual display
for window tests, golden-image options. Test folders mirror the packages (core, relief, viewer, bench, maptools,
studies)."""

from __future__ import annotations

import functools
import logging
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
import wgpu  # noqa: F401 - before logging.getLogger("wgpu") below: wgpu refuses a logger it did not create

IN_CI = bool(os.environ.get("CI"))


def pytest_addoption(parser):
    parser.addoption("--regen-golden", action="store_true",
                     help="rewrite tests/relief/golden/ from this adapter's renders")


def pytest_configure(config):
    config.addinivalue_line("markers", "requires_gpu: needs a wgpu adapter (skipped without one, failed in CI)")


def pytest_runtest_setup(item):
    if item.get_closest_marker("requires_gpu") and not adapter_summary():
        _missing("no wgpu adapter", "install mesa-vulkan-drivers")


ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session", autouse=True)
def isolated_user_dirs(tmp_path_factory):
    """Tests never touch the user's settings, map cache or temp folder. Generated maps go to a cache of the test
    suite's own, kept between runs (building 3D maps is slow on a software adapter); subprocesses
    inherit the variables."""
    saved = {name: os.environ.get(name) for name in ("WGPUVIEWER_CACHE_DIR", "WGPUVIEWER_CONFIG_DIR", "TMPDIR")}
    os.environ["WGPUVIEWER_CACHE_DIR"] = str(ROOT / ".pytest_cache" / "map-cache")
    os.environ["WGPUVIEWER_CONFIG_DIR"] = str(tmp_path_factory.mktemp("config"))
    # Temp files the code makes (saved tracebacks of internal errors, ...) stay in the test session's folder.
    saved_tempdir = tempfile.tempdir
    os.environ["TMPDIR"] = tempfile.tempdir = str(tmp_path_factory.mktemp("tmp"))
    yield
    tempfile.tempdir = saved_tempdir
    for name, value in saved.items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value


@functools.cache
def adapter_summary() -> str | None:
    """Summary of the adapter wgpu picks, or None. A subprocess: a broken driver can hang or crash."""
    code = "import wgpu; a = wgpu.gpu.request_adapter_sync(); print(a.summary if a else '')"
    try:
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        return None
    return out.stdout.strip() or None


def _missing(what: str, fix: str):
    if IN_CI:  # CI installs everything; a skip there would hide a broken setup
        pytest.fail(f"{what} in CI: {fix}")
    pytest.skip(f"{what}: {fix}")


@pytest.fixture(scope="session")
def adapter() -> str:
    summary = adapter_summary()
    if not summary:
        _missing("no wgpu adapter", "install mesa-vulkan-drivers")
    return summary


@pytest.fixture(scope="session")
def gpu(adapter):
    from wgpuviewer.core.gpu import get_gpu

    return get_gpu("auto", quiet=True)


class _Collect(logging.Handler):
    def __init__(self):
        super().__init__(level=logging.ERROR)
        self.records = []

    def emit(self, record):
        self.records.append(record)


@pytest.fixture(autouse=True)
def fail_on_gpu_error_logs():
    """rendercanvas/wgpu report some failures only as ERROR logs: make them test failures."""
    handler = _Collect()
    loggers = [logging.getLogger(name) for name in ("wgpu", "rendercanvas")]
    for logger in loggers:
        logger.addHandler(handler)
    yield
    for logger in loggers:
        logger.removeHandler(handler)
    if handler.records:
        pytest.fail("ERROR logged: " + "; ".join(f"{r.name}: {r.getMessage()}" for r in handler.records))


@pytest.fixture(scope="session")
def display():
    """An X display for window tests: the existing one, or a private Xvfb."""
    if os.environ.get("DISPLAY"):
        yield os.environ["DISPLAY"]
        return
    xvfb = shutil.which("Xvfb")
    if not xvfb:
        _missing("no display and no Xvfb", "install xvfb")
    r, w = os.pipe()
    proc = subprocess.Popen(
        [xvfb, "-displayfd", str(w), "-screen", "0", "1280x800x24", "-nolisten", "tcp"],
        pass_fds=(w,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )
    os.close(w)
    with os.fdopen(r) as f:
        number = f.readline().strip()
    if not number:
        proc.kill()
        _missing("Xvfb did not start", "check the xvfb installation")
    yield f":{number}"
    proc.terminate()
    proc.wait(timeout=10)
