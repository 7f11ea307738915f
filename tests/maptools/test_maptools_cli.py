"""maptools loading, writing, cache and CLI (generate / batch / check): exit codes, skipping, shards, atomicity."""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

import cv2
import numpy as np
import pytest

import maptools
from maptools import cache, cli, io, registry
from maptools.kinds.maxmip import cpu as maxmip_cpu
from maptools.kinds.maxmip.io import read_maxmip
from tests.maptools.helpers import smooth_tileable
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.images import read_height


@pytest.fixture
def inputs(tmp_path):
    h = smooth_tileable(24, 40, 1)
    d = tmp_path / "in"
    d.mkdir()
    np.save(d / "a.npy", h)
    cv2.imwrite(str(d / "b8.png"), np.round(h * 255).astype(np.uint8))
    (d / "sub").mkdir()
    cv2.imwrite(str(d / "sub" / "c16.png"), np.round(h * 65535).astype(np.uint16))
    return d, h


def leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.rglob("*") if p.name.endswith(".tmp"))


# -- loading -----------------------------------------------------------------------------------------

def test_load_8_16_bit_and_float(inputs):
    d, h = inputs
    assert np.array_equal(read_height(d / "a.npy"), h)
    h8 = read_height(d / "b8.png")
    assert h8.dtype == np.float32 and np.abs(h8 - h).max() <= 0.5 / 255 + 1e-7
    h16 = read_height(d / "sub" / "c16.png")
    assert np.abs(h16 - h).max() <= 0.5 / 65535 + 1e-7


def test_load_colour_channels(tmp_path):
    rgb = np.zeros((4, 5, 3), np.uint8)
    rgb[..., 0], rgb[..., 1], rgb[..., 2] = 10, 20, 30  # R, G, B
    p = tmp_path / "c.png"
    cv2.imwrite(str(p), rgb[..., ::-1])
    for ch, v in (("r", 10), ("g", 20), ("b", 30)):
        assert np.allclose(read_height(p, channel=ch), v / 255)
    luma = (0.2126 * 10 + 0.7152 * 20 + 0.0722 * 30) / 255  # auto: a colour file is read as its Rec. 709 luma
    assert np.allclose(read_height(p), luma) and np.allclose(read_height(p, channel="luma"), luma)
    with pytest.raises(UserError, match="different channels"):
        read_height(p, channel="grey")
    with pytest.raises(UserError, match="no alpha"):
        read_height(p, channel="a")
    np.save(tmp_path / "c.npy", rgb.astype(np.float32) / 255)
    assert np.allclose(read_height(tmp_path / "c.npy", channel="g"), 20 / 255)


def test_load_nan_policies(tmp_path):
    h = np.full((6, 7), 0.5, np.float32)
    h[0, 0] = 0.25
    h[2, 3] = np.nan
    h[0, 1] = np.inf
    np.save(tmp_path / "n.npy", h)
    with pytest.raises(UserError, match="--nan-policy"):
        read_height(tmp_path / "n.npy")
    z = read_height(tmp_path / "n.npy", nan_policy="zero")
    assert z[2, 3] == 0 and z[0, 1] == 0
    n = read_height(tmp_path / "n.npy", nan_policy="nearest")
    assert n[2, 3] == 0.5 and n[0, 1] == 0.25 and np.isfinite(n).all()
    np.save(tmp_path / "all.npy", np.full((2, 2), np.nan, np.float32))
    with pytest.raises(UserError, match="every texel"):
        read_height(tmp_path / "all.npy", nan_policy="nearest")


@pytest.mark.parametrize("name,content", [("x.png", b"not a png"), ("x.npy", b"garbage"), ("x.txt", b"1"),
                                          ("missing.npy", None)])
def test_load_bad_files(tmp_path, name, content):
    if content is not None:
        (tmp_path / name).write_bytes(content)
    with pytest.raises(UserError):
        read_height(tmp_path / name)


def test_load_out_of_range_float(tmp_path):
    np.save(tmp_path / "r.npy", np.full((3, 3), 2.0))
    with pytest.raises(UserError, match=r"\[0, 1\]"):
        read_height(tmp_path / "r.npy")


# -- writing -----------------------------------------------------------------------------------------

def test_writers_round_trip(tmp_path):
    h = smooth_tileable(20, 30, 2)
    n = maptools.generate("normal", h, backend="cpu")
    io.write_result(registry.KINDS["normal"], n, tmp_path / "n.npy")
    assert np.array_equal(np.load(tmp_path / "n.npy"), n)
    io.write_result(registry.KINDS["normal"], n, tmp_path / "n16.png", bits=16)
    back = cv2.imread(str(tmp_path / "n16.png"), cv2.IMREAD_UNCHANGED)[..., ::-1] / 65535 * 2 - 1
    assert back.shape == n.shape and np.abs(back - n).max() < 2e-5
    c = maptools.generate("complexity", h, backend="cpu")
    io.write_result(registry.KINDS["complexity"], c, tmp_path / "c.png")
    assert np.array_equal(cv2.imread(str(tmp_path / "c.png"), cv2.IMREAD_UNCHANGED), c)
    levels = maptools.generate("maxmip", h, backend="cpu")
    io.write_result(registry.KINDS["maxmip"], levels, tmp_path / "m.npz")
    assert all(np.array_equal(a, b) for a, b in zip(read_maxmip(tmp_path / "m.npz"), levels))
    with pytest.raises(UserError, match=".npz"):
        io.write_result(registry.KINDS["maxmip"], levels, tmp_path / "m.png")
    assert leftovers(tmp_path) == []


def failing_writer(f, result, ext, bits=8):
    f.write(b"partial data")
    raise RuntimeError("disk on fire")


def test_atomic_write_leaves_nothing_on_failure(tmp_path, monkeypatch):
    kind = dataclasses.replace(registry.KINDS["complexity"], writer=failing_writer)
    with pytest.raises(RuntimeError):
        io.write_result(kind, np.zeros((2, 2), np.uint8), tmp_path / "c.png")
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "c.png").write_bytes(b"old")  # an existing output survives a failed rewrite untouched
    with pytest.raises(RuntimeError):
        io.write_result(kind, np.zeros((2, 2), np.uint8), tmp_path / "c.png")
    assert (tmp_path / "c.png").read_bytes() == b"old" and leftovers(tmp_path) == []


# -- cache -------------------------------------------------------------------------------------------

def test_cached_generate(tmp_path, monkeypatch):
    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path / "cache"))
    h = smooth_tileable(16, 24, 3)
    first = cache.cached_generate("complexity", h, backend="cpu")
    files = list((tmp_path / "cache").rglob("*.npz"))
    assert len(files) == 1

    def boom(*a, **k):
        raise AssertionError("cache miss")

    monkeypatch.setattr(cache, "generate", boom)
    assert np.array_equal(cache.cached_generate("complexity", h, backend="cpu"), first)
    with pytest.raises(AssertionError, match="cache miss"):  # other options -> other key
        cache.cached_generate("complexity", h, backend="cpu", levels=8)
    monkeypatch.undo()
    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path / "cache"))
    levels = cache.cached_generate("maxmip", h, backend="cpu")
    again = cache.cached_generate("maxmip", h, backend="cpu")
    assert all(np.array_equal(a, b) for a, b in zip(levels, again))
    assert cache.cache_key("normal", h, {"a": 1}) != cache.cache_key("normal", h.astype(np.float64), {"a": 1})
    assert leftovers(tmp_path) == []


# -- CLI: generate / check -----------------------------------------------------------------------------

def test_cli_generate(inputs, tmp_path, capsys):
    d, h = inputs
    out = tmp_path / "out" / "n.npy"
    assert cli.main(["generate", "normal", str(d / "a.npy"), "-o", str(out), "--backend", "cpu",
                     "--strength", "2", "--y", "directx"]) == 0
    assert np.array_equal(np.load(out), maptools.generate("normal", h, backend="cpu", strength=2, y="directx"))
    assert cli.main(["generate", "complexity", str(d / "b8.png"), "-o", str(tmp_path / "c.png"),
                     "--backend", "cpu", "--levels", "16", "--border", "repeat"]) == 0
    assert cli.main(["generate", "maxmip", str(d / "a.npy"), "-o", str(tmp_path / "m.npz"), "--backend", "cpu"]) == 0


@pytest.mark.parametrize("argv,needle", [
    (["generate", "normal", "MISSING.png", "-o", "x.png", "--backend", "cpu"], "file not found"),
    (["generate", "complexity", "IN", "-o", "x.png", "--backend", "cpu", "--levels", "1"], "levels must be >= 2"),
    (["generate", "maxmip", "IN", "-o", "x.png", "--backend", "cpu"], ".npz"),
    (["batch", "IN", "-o", "OUT", "--shard", "3/2"], "--shard"),
    (["batch", "IN", "-o", "OUT", "--kinds", "normal,bogus"], "unknown map kind"),
    (["batch", "IN", "-o", "OUT", "--set", "complexity.gamma"], "--set"),
    # an option for a kind that is not selected would change nothing: refused, naming it
    (["batch", "IN", "-o", "OUT", "--kinds", "normal", "--set", "cone.max_ratio=4"],
     "--set 'cone.max_ratio=4': cone is not among the kinds selected (normal); add it to --kinds or drop the --set"),
    (["check", "IN", "--kinds", "normal,maxmip", "--set", "complexity.levels=8"],
     "complexity is not among the kinds selected (normal, maxmip)"),
    (["check", "IN", "--full", "--sample", "100"], "--full compares every value: drop --sample and --seed"),
    (["check", "IN", "--sample", "0"], "--sample 0: must be >= 1"),
    (["check", "IN", "--seed", "-1"], "--seed -1: must be >= 0"),
    # ... after its value is checked like a selected kind's
    (["batch", "IN", "-o", "OUT", "--kinds", "normal", "--set", "cone.max_ratio=-5"], "max_ratio"),
    (["batch", "IN", "-o", "OUT", "--kinds", "cone", "--set", "cone.max_ratio=-5"], "max_ratio"),
    (["batch", "IN", "-o", "OUT", "--kinds", "normal", "--set", "complexity.bogus=1"], "unknown option(s) bogus"),
])
def test_cli_user_errors_exit_2(inputs, tmp_path, capsys, argv, needle):
    d, _ = inputs
    argv = [str(d / "a.npy") if a == "IN" else str(tmp_path / "o") if a == "OUT" else a for a in argv]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("maptools: error:") and needle in err[0]
    assert "Traceback" not in err[0]


def test_cli_usage_error_exit_2(capsys):
    assert cli.main(["generate", "bogus", "x", "-o", "y"]) == 2
    assert cli.main(["frobnicate"]) == 2


@pytest.mark.requires_gpu
def test_cli_check(inputs, capsys, monkeypatch):
    d, _ = inputs
    assert cli.main(["check", str(d / "b8.png")]) == 0
    out = capsys.readouterr().out
    assert out.count("OK") == len(registry.KINDS) and "MISMATCH" not in out
    bad = dataclasses.replace(registry.KINDS["maxmip"], gpu=lambda h: [x + 1 for x in maxmip_cpu.maxmip(h)])
    monkeypatch.setitem(registry.KINDS, "maxmip", bad)
    assert cli.main(["check", str(d / "a.npy"), "--kinds", "maxmip"]) == 1
    assert "MISMATCH" in capsys.readouterr().out


def test_cli_check_without_adapter_exit_2(inputs, monkeypatch, capsys):
    from maptools import gpu
    from wgpuviewer.core.errors import NoAdapterError

    def none(*a, **k):
        raise NoAdapterError("no GPU adapter found; install mesa-vulkan-drivers")

    monkeypatch.setattr(gpu, "runner", none)
    assert cli.main(["check", str(inputs[0] / "a.npy")]) == 2
    assert "no GPU adapter" in capsys.readouterr().err


# -- CLI: batch ----------------------------------------------------------------------------------------

def batch(*args) -> int:
    return cli.main(["batch", *map(str, args), "--backend", "cpu"])


def test_batch_generates_then_skips(inputs, tmp_path, capsys):
    d, h = inputs
    out = tmp_path / "out"
    assert batch(d, "-o", out) == 0
    names = sorted(p.name for p in out.iterdir() if not p.name.endswith(".json"))
    assert names == sorted(f"{s}.{k}{registry.KINDS[k].extensions[0]}"
                           for s in ("a", "b8", "c16") for k in registry.KINDS)
    capsys.readouterr()
    stamp = {p: p.stat().st_mtime_ns for p in out.iterdir()}
    assert batch(d, "-o", out) == 0
    total = 3 * len(registry.KINDS)
    assert f"0 generated, {total} up to date, 0 failed" in capsys.readouterr().out
    assert stamp == {p: p.stat().st_mtime_ns for p in out.iterdir()}
    # changed content, changed options, --force -> regenerated
    np.save(d / "a.npy", h[::-1].copy())
    assert batch(d, "-o", out, "--set", "complexity.levels=8") == 0
    changed = len(registry.KINDS) + 2  # every kind of a.npy, complexity of the other two
    assert f"{changed} generated, {total - changed} up to date" in capsys.readouterr().out
    assert batch(d, "-o", out, "--set", "complexity.levels=8", "--force", "--jobs", "3") == 0
    assert f"{total} generated, 0 up to date" in capsys.readouterr().out
    meta = json.loads((out / "a.normal.png.json").read_text())
    assert meta["kind"] == "normal" and meta["version"] == maptools.VERSION
    assert leftovers(out) == []


def test_batch_bad_input_reported_and_continues(inputs, tmp_path, capsys):
    d, _ = inputs
    (d / "broken.png").write_bytes(b"not an image")
    nan = np.full((4, 4), 0.5, np.float32)
    nan[1, 1] = np.nan
    np.save(d / "nan.npy", nan)
    out = tmp_path / "out"
    assert batch(d, tmp_path / "nope", "-o", out, "--kinds", "maxmip") == 1
    text = capsys.readouterr().out
    assert text.count("FAILED") == 3 and "3 generated" in text
    assert {p.name for p in out.glob("*.npz")} == {"a.maxmip.npz", "b8.maxmip.npz", "c16.maxmip.npz"}
    assert leftovers(out) == []
    assert batch(d, "-o", out, "--kinds", "maxmip", "--nan-policy", "zero") == 1  # only broken.png fails now


def test_batch_shards_partition_inputs(tmp_path, capsys):
    d = tmp_path / "in"
    d.mkdir()
    for i in range(11):
        np.save(d / f"h{i:02d}.npy", np.full((3, 5), i / 10, np.float32))
    seen = []
    for i in range(3):
        out = tmp_path / f"out{i}"
        assert batch(d, "-o", out, "--kinds", "maxmip", "--shard", f"{i}/3") == 0
        seen += [p.name.split(".")[0] for p in out.glob("*.npz")]
    assert sorted(seen) == [f"h{i:02d}" for i in range(11)]
    files, _ = cli.collect_inputs([str(d)])
    parts = [cli.shard(files, i, 4) for i in range(4)]
    assert sorted(sum(parts, []), key=str) == files and sum(map(len, parts)) == len(files)


def test_batch_failing_writer_leaves_no_partial_files(inputs, tmp_path, monkeypatch, capsys):
    d, _ = inputs
    monkeypatch.setitem(registry.KINDS, "complexity",
                        dataclasses.replace(registry.KINDS["complexity"], writer=failing_writer))
    out = tmp_path / "out"
    assert batch(d, "-o", out, "--kinds", "normal,complexity") == 3  # an exception that is no UserError: a bug
    assert "disk on fire" in capsys.readouterr().out
    assert not list(out.glob("*complexity*")) and len(list(out.glob("*.normal.png"))) == 3
    assert leftovers(out) == [] and not [p for p in out.iterdir() if p.name.startswith(".")]
    monkeypatch.undo()
    assert batch(d, "-o", out, "--kinds", "normal,complexity") == 0  # the failed jobs are redone, the rest skipped
    assert "3 generated, 3 up to date" in capsys.readouterr().out


@pytest.mark.requires_gpu
def test_batch_on_gpu(inputs, tmp_path, capsys):
    d, _ = inputs
    assert cli.main(["batch", str(d), "-o", str(tmp_path / "out"), "--backend", "gpu", "--jobs", "2"]) == 0
    assert f"{3 * len(registry.KINDS)} generated" in capsys.readouterr().out


def test_entry_point_declared():
    text = (Path(__file__).resolve().parents[2] / "pyproject.toml").read_text()
    assert 'maptools = "maptools.cli:main"' in text
    assert os.path.isfile(Path(maptools.__file__).with_name("cli.py"))
