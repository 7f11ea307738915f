"""Atomicity under a real kill: SIGKILL a running `maptools batch`, then only complete outputs may remain."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import maptools
from maptools import cli

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs SIGKILL")
KINDS = "normal,maxmip,distance"


def test_sigkill_mid_batch_leaves_only_complete_outputs(tmp_path, capsys):
    rng = np.random.default_rng(0)
    src = tmp_path / "in"
    src.mkdir()
    maps = {}
    for n in range(40):
        maps[f"h{n:02d}"] = rng.random((64, 64)).astype(np.float32)
        np.save(src / f"h{n:02d}.npy", maps[f"h{n:02d}"])
    out = tmp_path / "out"
    argv = [sys.executable, "-c", "import sys; from maptools.cli import main; sys.exit(main())", "batch", str(src),
            "-o", str(out), "--kinds", KINDS, "--backend", "cpu", "--set", "distance.slices=16"]
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and proc.poll() is None:
            if len(list(out.glob("*.json"))) >= 6:  # a few complete outputs: we are midway
                break
            time.sleep(0.01)
        assert proc.poll() is None, "batch finished before it could be killed; give it more work"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == -signal.SIGKILL
    names = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    # a kill can leave at most a hidden temp file per job running at that moment, never a partial output
    temps = [p.name for p in out.iterdir() if p.name.startswith(".")]
    assert all(t.endswith(".tmp") for t in temps) and len(temps) <= 3, temps
    outputs = [out / n for n in names if not n.endswith(".json")]
    assert 0 < len(outputs) < 40 * 3
    for p in outputs:  # every output present is complete: it loads and equals a fresh single generate
        stem, kind = p.name.split(".")[:2]
        if kind == "maxmip":
            from maptools.kinds.maxmip.io import read_maxmip

            got, want = read_maxmip(p), maptools.generate("maxmip", maps[stem], backend="cpu")
            assert all(np.array_equal(a, b) for a, b in zip(got, want))
        elif kind == "normal":
            import cv2

            img = cv2.imread(str(p), cv2.IMREAD_UNCHANGED)
            assert img is not None and img.shape == (64, 64, 3)
        else:
            want = maptools.generate(kind, maps[stem], backend="cpu", slices=16)
            assert np.array_equal(np.load(p), want)
    done = {n[: -len(".json")] for n in names if n.endswith(".json")}
    assert done <= set(names)  # a sidecar only ever follows its complete output
    # the re-run completes the rest and skips what was finished
    capsys.readouterr()
    code = cli.main(["batch", str(src), "-o", str(out), "--kinds", KINDS, "--backend", "cpu",
                     "--set", "distance.slices=16", "--jobs", "2"])
    assert code == 0
    assert f"{120 - len(done)} generated, {len(done)} up to date, 0 failed" in capsys.readouterr().out
    assert len(list(out.glob("*.json"))) == 40 * 3
    assert not [p for p in out.iterdir() if p.name.startswith(".")]
    assert cli.main(["batch", str(src), "-o", str(out), "--kinds", KINDS, "--backend", "cpu",
                     "--set", "distance.slices=16"]) == 0
    assert "0 generated, 120 up to date" in capsys.readouterr().out
