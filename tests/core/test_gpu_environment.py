"""The Python API prepares the drivers' environment on its first adapter request, as the CLIs do: no Mesa
``XDG_RUNTIME_DIR`` lines from a script that only imports the library."""

from __future__ import annotations

import os
import stat
import subprocess
import sys

import pytest

from wgpuviewer.core import gpu as core_gpu


@pytest.mark.parametrize("value", [None, "relative/dir", "/nonexistent-runtime-dir"])
def test_the_first_adapter_request_sets_a_private_runtime_dir(value, monkeypatch):
    if os.name != "posix":
        pytest.skip("XDG_RUNTIME_DIR is a POSIX variable")
    if value is None:
        monkeypatch.delenv("XDG_RUNTIME_DIR", raising=False)
    else:
        monkeypatch.setenv("XDG_RUNTIME_DIR", value)
    monkeypatch.setattr(core_gpu.wgpu.gpu, "enumerate_adapters_sync", lambda: [])  # no driver is loaded here
    assert core_gpu.list_adapters() == []
    path = os.environ["XDG_RUNTIME_DIR"]
    info = os.stat(path)
    assert os.path.isabs(path) and stat.S_IMODE(info.st_mode) == 0o700 and info.st_uid == os.getuid()
    core_gpu.list_adapters()
    assert os.environ["XDG_RUNTIME_DIR"] == path  # a valid folder is kept


@pytest.mark.requires_gpu
def test_a_script_using_the_api_prints_no_driver_lines():
    env = {name: value for name, value in os.environ.items() if name != "XDG_RUNTIME_DIR"}
    code = ("import numpy as np\n"
            "from wgpuviewer.accuracy import measure\n"
            "print(measure('pom', np.full((8, 8), 0.5), 30.0, rays=8).rays)\n")
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "8"
    assert "XDG_RUNTIME_DIR" not in done.stderr, done.stderr
