"""Batches never read their own outputs, go on past internal errors (exit 3), refuse an empty --kinds; the map
cache is capped (least recently used maps evicted), shown and cleaned by `maptools cache`, and an unwritable
cache is a warning, not an error."""

from __future__ import annotations

import os
import re
import time

import numpy as np
import pytest

from maptools import cache, cli
from tests.maptools.helpers import smooth_tileable


@pytest.fixture
def heights(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    for i in range(3):
        np.save(src / f"h{i}.npy", smooth_tileable(16, 20, i))
    return src


def batch(*argv) -> int:
    return cli.main(["batch", *map(str, argv), "--kinds", "normal,complexity", "--backend", "cpu"])


def names(folder) -> list[str]:
    return sorted(p.name for p in folder.rglob("*") if p.is_file())


@pytest.mark.parametrize("where", ["inside", "same"])
def test_outputs_are_never_inputs(heights, where, capsys):
    out = heights / "maps" if where == "inside" else heights
    assert batch(heights, "-o", out) == 0
    first = names(heights)
    assert batch(heights, "-o", out) == 0  # again: only the three inputs, all up to date
    assert "0 generated, 6 up to date, 0 failed" in capsys.readouterr().out
    assert names(heights) == first
    assert not [n for n in first if n.count(".normal") + n.count(".complexity") > 1]  # no x.normal.normal.png
    # outputs written elsewhere are recognised by their sidecars when that folder is searched later
    assert batch(out, heights, "-o", heights / "elsewhere") == 0
    assert "6 generated, 0 up to date, 0 failed" in capsys.readouterr().out


def test_outputs_without_sidecars_in_the_output_folder_are_not_inputs(heights, capsys):
    assert batch(heights, "-o", heights) == 0
    for sidecar in heights.glob("*.json"):  # as after a kill between an output and its sidecar
        sidecar.unlink()
    assert batch(heights, "-o", heights) == 0
    assert "6 generated, 0 up to date, 0 failed" in capsys.readouterr().out


@pytest.mark.parametrize("kinds", ["", ",", " , "])
def test_an_empty_kinds_list_is_an_error(heights, tmp_path, kinds, capsys):
    for command in (["batch", str(heights), "-o", str(tmp_path / "o")], ["check", str(heights / "h0.npy")]):
        assert cli.main([*command, "--kinds", kinds]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"--kinds {kinds!r}: expected a comma-separated list" in err[0]
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


def test_an_internal_error_in_one_job_exits_3_and_the_batch_goes_on(heights, tmp_path, monkeypatch, capsys):
    real = cli.generate
    traces = tmp_path / "traces"
    traces.mkdir()
    monkeypatch.setattr(cli, "save_traceback", lambda prog, error: cli_save(prog, error, traces))

    def generate(kind, height, **kw):
        if kind == "complexity" and np.array_equal(height, np.load(heights / "h1.npy")):
            raise TypeError("a bug in one kernel")
        return real(kind, height, **kw)

    monkeypatch.setattr(cli, "generate", generate)
    assert batch(heights, "-o", tmp_path / "maps") == 3
    out = capsys.readouterr().out
    assert "5 generated, 0 up to date, 1 failed (1 internal error(s): please report them)" in out
    line = next(row for row in out.splitlines() if "INTERNAL" in row)
    assert "h1.npy" in line and "TypeError: a bug in one kernel" in line and str(traces) in line
    assert len(list(traces.iterdir())) == 1


def cli_save(prog, error, folder):
    path = folder / f"{prog}-traceback.txt"
    path.write_text(f"{type(error).__name__}: {error}")
    return path


@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path / "cache"))
    return tmp_path / "cache"


def test_the_cache_evicts_the_least_recently_used_maps_beyond_its_cap(cache_dir, monkeypatch):
    maps = [smooth_tileable(32, 32, i) for i in range(5)]
    cache.cached_generate("normal", maps[0], backend="cpu")
    size = cache.entries()[0].size
    monkeypatch.setenv(cache.CACHE_MAX_ENV, str(3 * size + size // 2))  # room for three maps
    for i, h in enumerate(maps[1:3], start=1):
        cache.cached_generate("normal", h, backend="cpu")
        old = time.time() - 100 + i
        os.utime(cache.entries()[-1].path, (old, old))
    os.utime(cache.entries()[0].path, (time.time() - 1000,) * 2)  # maps[0] is the least recently used ...
    cache.cached_generate("normal", maps[0], backend="cpu")  # ... until a hit touches it
    cache.cached_generate("normal", maps[3], backend="cpu")
    cache.cached_generate("normal", maps[4], backend="cpu")
    kept = {e.path for e in cache.entries()}
    assert len(kept) == 3 and sum(e.size for e in cache.entries()) <= 3 * size + size // 2
    key = {i: cache.cache_path("normal", cache.cache_key("normal", h, cache.get_kind("normal").resolve({})))
           for i, h in enumerate(maps)}
    assert kept == {key[0], key[3], key[4]}  # 1 and 2 were the least recently used


def test_cache_info_and_clean(cache_dir, capsys):
    for i in range(3):
        cache.cached_generate("complexity", smooth_tileable(16, 16, i), backend="cpu")
    cache.cached_generate("maxmip", smooth_tileable(16, 16, 0), backend="cpu")
    old = time.time() - 3 * 86400
    for entry in cache.entries()[:2]:
        os.utime(entry.path, (old, old))
    assert cli.main(["cache", "info"]) == 0
    out = capsys.readouterr().out
    assert f"map cache: {cache_dir} ($WGPUVIEWER_CACHE_DIR)" in out and "size cap: 2.0 GiB" in out
    assert "complexity" in out and "maxmip" in out and "total: 4 maps" in out
    assert cli.main(["cache", "clean", "--older-than", "2d"]) == 0
    assert "removed 2 maps" in capsys.readouterr().out and len(cache.entries()) == 2
    (cache_dir / "complexity" / "ab").mkdir(parents=True, exist_ok=True)
    (cache_dir / "complexity" / "ab" / ".abc.npz.x1y2z3w4.tmp").write_bytes(b"left by a kill")
    assert cli.main(["cache", "clean"]) == 0
    assert "removed 2 maps" in capsys.readouterr().out and cache.entries() == []
    assert not list(cache_dir.rglob("*.tmp"))


@pytest.mark.parametrize("argv,env,needle", [
    (["cache", "clean", "--older-than", "soon"], {}, "--older-than 'soon': expected an age"),
    (["cache", "info"], {"WGPUVIEWER_CACHE_MAX": "lots"}, "$WGPUVIEWER_CACHE_MAX = 'lots': expected a size"),
    (["cache", "frobnicate"], {}, "invalid choice: 'frobnicate'"),
])
def test_cache_user_errors(cache_dir, monkeypatch, capsys, argv, env, needle):
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0], err


def test_an_unwritable_cache_is_a_warning_and_the_map_is_still_made(tmp_path, monkeypatch, caplog):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    monkeypatch.setenv(cache.CACHE_ENV, str(blocker / "maps"))
    monkeypatch.setattr(cache, "_warned", set())
    h = smooth_tileable(16, 16, 4)
    for _ in range(2):
        got = cache.cached_generate("normal", h, backend="cpu")
        assert got.shape == (16, 16, 3)
    warnings = [r.getMessage() for r in caplog.records if r.name == "maptools.cache"]
    assert len(warnings) == 1, warnings  # once per process
    assert f"map cache {blocker / 'maps'} cannot be written" in warnings[0]
    assert "set WGPUVIEWER_CACHE_DIR to a writable folder" in warnings[0]
    assert blocker.read_text() == "not a folder"


def test_render_with_an_unwritable_cache_warns_once_and_renders(tmp_path, monkeypatch, capsys, adapter):
    from wgpuviewer import cli as wgpuviewer_cli
    from wgpuviewer import textures

    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setenv(cache.CACHE_ENV, str(blocker / "maps"))
    monkeypatch.setattr(cache, "_warned", set())
    textures.clear_cache()
    out = tmp_path / "x.png"
    assert wgpuviewer_cli.main(["render", "-o", str(out), "--size", "32x24", "--technique", "pom_adaptive"]) == 0
    err = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert err == [f"wgpuviewer: warning: map cache {blocker / 'maps'} cannot be written (Not a directory); "
                   "maps are rebuilt on every run: set WGPUVIEWER_CACHE_DIR to a writable folder"], err
    assert out.is_file()


def test_an_edited_kernel_changes_the_cache_and_batch_keys(monkeypatch):
    """The key holds the kind's composed kernel source: an edit of a kernel, or of a file it includes, never
    serves a map the old kernel built; kinds that do not run the edited file keep their keys."""
    import argparse

    from maptools.volume import gpu as volume_gpu
    from wgpuviewer.core import wgsl

    h = smooth_tileable(16, 16, 0)
    args = argparse.Namespace(channel="auto", nan_policy="error", bits=8)
    kinds = ("normal", "complexity", "distance_refined", "cone")

    def keys():
        return {k: (cache.cache_key(k, h, cache.get_kind(k).resolve({})), cli.job_key("d", k, {}, args, ".npy"))
                for k in kinds}

    before = keys()
    read = wgsl.read_wgsl
    for edited, changed in (("common/sobel.wgsl", {"normal", "complexity"}),
                            (str(volume_gpu.KERNEL.path), {"distance_refined"})):
        monkeypatch.setattr(wgsl, "read_wgsl", lambda name, edited=edited: read(name) + ("// edited\n" if name == edited
                                                                                     else ""))
        after = keys()
        assert {k for k in kinds if after[k][0] != before[k][0]} == changed, edited
        assert {k for k in kinds if after[k][1] != before[k][1]} == changed, edited
    monkeypatch.undo()
    assert keys() == before


@pytest.mark.requires_gpu
def test_each_kind_declares_every_kernel_its_gpu_path_runs(monkeypatch):
    """The key hashes the kernels a kind declares: they must be all that its GPU path dispatches."""
    from maptools import gpu, registry

    ran: set[str] = set()
    dispatch = gpu.MapGpu.dispatch
    monkeypatch.setattr(gpu.MapGpu, "dispatch", lambda self, enc, file, *a, **k: (ran.add(file),
                                                                                   dispatch(self, enc, file, *a, **k)))
    h = smooth_tileable(16, 16, 0)
    for name, kind in registry.KINDS.items():
        ran.clear()
        options = {"progress": False} if name == "distance_refined" else {}
        kind.gpu(h, **kind.resolve({}), **options)
        assert ran == set(kind.kernels), name


def _entry(kind: str, h):
    return cache.cache_path(kind, cache.cache_key(kind, h, cache.get_kind(kind).resolve({})))


def _rewritten(path, change) -> None:
    """The entry at ``path`` written again as a well-formed file, its arrays passed through ``change``, its key and
    checksum kept."""
    with np.load(path) as z:
        arrays = {name: z[name] if name in ("key", "sha256") else change(z[name]) for name in z.files}
    with open(path, "wb") as f:
        np.savez(f, **arrays)


@pytest.mark.parametrize("kind,damage,reason", [
    ("normal", "overwrite", "checksum mismatch|unreadable: BadZipFile: Bad CRC-32"),  # data bytes, header intact
    ("maxmip", "overwrite", "checksum mismatch|unreadable: BadZipFile: Bad CRC-32"),
    ("cone", "rewrite", "checksum mismatch"),  # a well-formed file with other data under the stored checksum
    ("normal", "truncate", "unreadable"),
    ("complexity", "swap", "it holds another map"),  # another entry's file in its place: a valid map, not this one
])
def test_a_damaged_cache_entry_is_rebuilt_with_one_warning(cache_dir, caplog, kind, damage, reason):
    h, other = smooth_tileable(16, 16, 5), smooth_tileable(16, 16, 6)
    fresh = cache.generate(kind, h, backend="cpu")
    cache.cached_generate(kind, h, backend="cpu")
    path = _entry(kind, h)
    data = bytearray(path.read_bytes())
    if damage == "overwrite":
        data[len(data) // 2: len(data) // 2 + 64] = bytes(range(64))
    elif damage == "truncate":
        data = data[: len(data) // 2]
    elif damage == "swap":
        cache.cached_generate(kind, other, backend="cpu")
        data = bytearray(_entry(kind, other).read_bytes())
    if damage == "rewrite":
        _rewritten(path, lambda a: a + 1)
    else:
        path.write_bytes(bytes(data))
    caplog.clear()
    got = cache.cached_generate(kind, h, backend="cpu")
    same = (all(np.array_equal(a, b) for a, b in zip(got, fresh, strict=True)) if kind == "maxmip"
            else np.array_equal(got, fresh))
    assert same, f"served the damaged {kind} map"
    warnings = [r.getMessage() for r in caplog.records if r.name == "maptools.cache"]
    assert len(warnings) == 1 and re.match(rf"map cache: {re.escape(str(path))} is damaged \(({reason})", warnings[0]) \
        and warnings[0].endswith("rebuilding it"), warnings
    caplog.clear()
    again = cache.cached_generate(kind, h, backend="cpu")  # rebuilt: a clean hit now
    assert [r for r in caplog.records if r.name == "maptools.cache"] == []
    assert np.array_equal(again[0] if kind == "maxmip" else again, fresh[0] if kind == "maxmip" else fresh)


@pytest.mark.parametrize("where", ["file", "under a file"])
@pytest.mark.parametrize("action", ["info", "clean"])
def test_cache_info_and_clean_refuse_a_cache_path_that_is_not_a_folder(tmp_path, monkeypatch, capsys, where,
                                                                          action):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    monkeypatch.setenv(cache.CACHE_ENV, str(blocker if where == "file" else blocker / "maps"))
    assert cli.main(["cache", action]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"maptools: error: map cache {blocker}"), err
    assert "not a folder; set $WGPUVIEWER_CACHE_DIR to a folder" in err[0], err
    assert blocker.read_text() == "not a folder"


# -- batch records and named maps ----------------------------------------------------------------------------------

def test_batch_records_what_each_map_was_built_from(heights, tmp_path, capsys):
    import hashlib
    import json

    from wgpuviewer.core.sidecar import read_record

    out = tmp_path / "maps"
    assert batch(heights / "h0.npy", "-o", out) == 0
    record = read_record(out / "h0.normal.png")
    assert (record.kind, record.channel, record.version) == ("normal", "auto", cache.VERSION)
    assert record.options == cache.get_kind("normal").resolve({})
    assert record.input_sha256 == hashlib.sha256((heights / "h0.npy").read_bytes()).hexdigest()
    assert record.output_sha256 == hashlib.sha256((out / "h0.normal.png").read_bytes()).hexdigest()
    # a record without the fields a scene checks (an older batch's) is not up to date: the map is made again
    old = {k: v for k, v in json.loads((out / "h0.normal.png.json").read_text()).items()
           if k not in ("channel", "output_sha256")}
    (out / "h0.normal.png.json").write_text(json.dumps(old))
    capsys.readouterr()
    assert batch(heights / "h0.npy", "-o", out) == 0
    assert "1 generated, 1 up to date, 0 failed" in capsys.readouterr().out
    assert read_record(out / "h0.normal.png") == record


def test_recording_says_where_each_map_came_from(cache_dir):
    h = smooth_tileable(16, 16, 7)
    with cache.recording() as outer:
        cache.cached_generate("normal", h, backend="cpu")
        with cache.recording() as inner:
            cache.cached_generate("normal", h, backend="cpu")
    assert inner == [cache.Served("normal", "cache")]
    assert outer == [cache.Served("normal", "built"), cache.Served("normal", "cache")]


@pytest.fixture
def named(tmp_path, cache_dir):
    """h.npy (16x16), its cone map (max_ratio 8) and complexity map (border repeat, 16-bit PNG) as maptools batch
    writes them; (height, folder)."""
    h = smooth_tileable(16, 16, 8)
    np.save(tmp_path / "h.npy", h)
    assert cli.main(["batch", str(tmp_path / "h.npy"), "-o", str(tmp_path / "maps"), "--kinds", "cone,complexity",
                     "--set", "cone.max_ratio=8", "--set", "complexity.border=repeat", "--bits", "16",
                     "--backend", "cpu"]) == 0
    return h, tmp_path / "maps"


def test_a_named_map_is_served_when_its_record_matches_the_request(named):
    h, maps = named
    files = {"cone": (maps / "h.cone.npy", "here"), "complexity": (maps / "h.complexity.png", "there")}
    with cache.serving(files), cache.recording() as served:
        cone = cache.cached_generate("cone", h, backend="cpu", max_ratio=8)
        levels = cache.cached_generate("complexity", h, backend="cpu", border="repeat")
        cache.cached_generate("normal", h, backend="cpu")  # a kind the scene does not name: built as ever
    assert np.array_equal(cone, np.load(maps / "h.cone.npy"))
    assert levels.dtype == np.uint8 and np.array_equal(levels, cache.generate("complexity", h, backend="cpu",
                                                                              border="repeat"))
    assert served == [cache.Served("cone", "file"), cache.Served("complexity", "file"),
                      cache.Served("normal", "built")]
    assert {e.kind for e in cache.entries()} == {"normal"}  # named maps are not copied into the cache


@pytest.mark.parametrize("case,needle", [
    ("options", "here: built with max_ratio=8.0, filter=bilinear; the renderer needs max_ratio=32.0, filter=nearest: "
                "rebuild it (maptools batch {h} -o {maps} --kinds cone --set cone.max_ratio=32.0 "
                "--set cone.filter=nearest)"),
    ("one option", "here: built with filter=bilinear; the renderer needs filter=nearest: rebuild it (maptools batch "
                   "{h} -o {maps} --kinds cone --set cone.max_ratio=8.0 --set cone.filter=nearest)"),  # 8 kept
    ("version", "here: built by maptools-0, this is {version}: rebuild it (maptools batch {h} -o {maps} --kinds cone "
                "--force)"),
    ("bytes", "here: h.cone.npy changed after maptools batch wrote it (its sha256 is not its record's): rebuild it"),
    ("kind", "here: is a complexity map (its record says so); expected a cone map"),
    ("size", "here: a map of 16x16 texels; the height map is 8x4"),
    ("record", "here: {maps}/h.cone.npy.json: not found; name a map written by maptools batch"),
])
def test_a_named_map_that_is_not_the_map_asked_for_is_refused(named, case, needle):
    import dataclasses

    from wgpuviewer.core.sidecar import read_record, write_record

    h, maps = named
    path = maps / "h.cone.npy"
    options = {"max_ratio": 8}
    if case == "options":
        options = {"max_ratio": 32, "filter": "nearest"}
    elif case == "one option":
        options = {"max_ratio": 8, "filter": "nearest"}
    elif case == "version":
        write_record(path, dataclasses.replace(read_record(path), version="maptools-0"))
    elif case == "bytes":
        np.save(path, np.load(path) * 0.5)
    elif case == "kind":
        path = maps / "h.complexity.png"
    elif case == "size":
        h = h[:4, :8]
    else:
        (maps / "h.cone.npy.json").unlink()
    with cache.serving({"cone": (path, "here")}), pytest.raises(cache.UserError) as error:
        cache.cached_generate("cone", h, backend="cpu", **options)
    expected = needle.format(h=maps.parent / "h.npy", maps=maps, version=cache.VERSION)
    assert str(error.value) == expected if case in ("options", "one option", "version") else expected in str(error.value), \
        str(error.value)
