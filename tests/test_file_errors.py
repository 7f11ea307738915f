"""Bad texture files, wherever they are met: one line naming the scene file, the key, the value and the reason,
exit 2, also when the problem shows only when the data is decoded (lazily) or when a map derived from the height
map cannot be built. Members: empty, truncated, corrupt, folder, too large, BOM; scene loading, `render`, the
scripted `view`, maptools generate/check/batch."""

from __future__ import annotations

import shutil

import cv2
import numpy as np
import pytest

from maptools import cli as maptools_cli
from tests.relief.scenes import material_scene
from wgpuviewer import cli, textures
from wgpuviewer.core.errors import UserError
from wgpuviewer.scene import load_scene


@pytest.fixture(autouse=True)
def _fresh_textures():
    textures.clear_cache()
    yield
    textures.clear_cache()


@pytest.fixture
def files(tmp_path):
    rng = np.random.default_rng(2)
    good = tmp_path / "good.png"
    cv2.imwrite(str(good), rng.integers(0, 255, (64, 64, 3), dtype=np.uint8))
    data = good.read_bytes()
    (tmp_path / "empty.png").write_bytes(b"")
    (tmp_path / "empty.npy").write_bytes(b"")
    (tmp_path / "cut.png").write_bytes(data[: len(data) // 2])
    (tmp_path / "folder.png").mkdir()
    # A valid signature, header and end chunk around damaged image data: only decoding finds out.
    start, end = data.index(b"IDAT") + 4, data.index(b"IEND") - 8
    (tmp_path / "corrupt.png").write_bytes(data[:start] + bytes(end - start) + data[end:])
    return tmp_path


def scene_file(folder, albedo="good.png", height="good.png", name="s.toml"):
    path = folder / name
    path.write_text(material_scene(["basic", "pom", "distance"], f'albedo = "{albedo}"\nheight = "{height}"'))
    return path


def one_line(capsys, prog="wgpuviewer") -> str:
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip() and not line.startswith("notice:")]
    assert len(err) == 1 and "Traceback" not in err[0], err
    assert err[0].startswith(f"{prog}: error: "), err
    return err[0]


@pytest.mark.parametrize("key,name,reason", [
    ("albedo", "empty.png", "empty file (0 bytes)"),
    ("height", "empty.npy", "empty file (0 bytes)"),
    ("height", "cut.png", "truncated PNG"),
    ("albedo", "folder.png", "is a directory"),
])
def test_bad_files_are_reported_against_their_scene_key(files, key, name, reason, capsys, monkeypatch):
    path = scene_file(files, **{key: name})
    expected = f"{path}: materials.m.{key} = '{name}': {reason}"
    with pytest.raises(UserError) as error:
        load_scene(path)
    assert str(error.value).startswith(expected), str(error.value)
    assert cli.main(["render", str(path), "-o", str(files / "out.png"), "--size", "16x16"]) == 2
    assert one_line(capsys).startswith(f"wgpuviewer: error: {expected}")
    monkeypatch.setenv("DISPLAY", ":0")  # the scripted viewer fails the same way, before any window opens
    assert cli.main(["view", str(path), "--frames", "2"]) == 2
    assert one_line(capsys).startswith(f"wgpuviewer: error: {expected}")
    assert not (files / "out.png").exists()


def test_problems_found_only_when_decoding_name_the_key_too(files, capsys, adapter):
    path = scene_file(files, height="corrupt.png")
    scene = load_scene(path)  # the header is fine
    with pytest.raises(UserError) as error:
        textures.load_height(scene.materials["m"].height)
    assert str(error.value).startswith(f"{path}: materials.m.height = 'corrupt.png': cannot decode image")
    textures.clear_cache()
    assert cli.main(["render", str(path), "-o", str(files / "x.png"), "--size", "16x16", "--technique", "pom"]) == 2
    assert f"{path}: materials.m.height = 'corrupt.png': cannot decode image" in one_line(capsys)
    # a technique that needs no height map still renders
    assert cli.main(["render", str(path), "-o", str(files / "x.png"), "--size", "16x16", "--technique", "basic"]) == 0


def test_a_height_map_too_large_for_a_derived_map_is_reported_against_the_height_key(files, capsys, gpu):
    limit = gpu.device.limits["max-texture-dimension-3d"]
    cv2.imwrite(str(files / "wide.png"), np.full((2, limit + 1), 128, np.uint8))
    path = scene_file(files, height="wide.png")
    assert cli.main(["render", str(path), "-o", str(files / "x.png"), "--size", "16x16",
                     "--technique", "distance"]) == 2
    line = one_line(capsys)
    assert line.startswith(f"wgpuviewer: error: {path}: materials.m.height = 'wide.png': its distance map cannot "
                           "be built:"), line
    assert f"3D limit of {limit}" in line

def test_a_byte_order_mark_gets_a_hint(files):
    path = scene_file(files)
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    with pytest.raises(UserError, match="byte-order mark.*save the file as UTF-8 without BOM"):
        load_scene(path)


@pytest.mark.parametrize("name,reason", [("empty.png", "empty file (0 bytes)"), ("cut.png", "truncated PNG"),
                                         ("corrupt.png", "cannot decode image"), ("folder.png", "is a directory")])
def test_maptools_reports_bad_inputs_in_one_line(files, name, reason, capsys):
    src = files / name
    assert maptools_cli.main(["generate", "normal", str(src), "-o", str(files / "n.png"), "--backend", "cpu"]) == 2
    assert one_line(capsys, "maptools").startswith(f"maptools: error: {src}: {reason}")
    assert maptools_cli.main(["check", str(src), "--kinds", "normal"]) == 2
    assert f"{src}: {reason}" in one_line(capsys, "maptools")


def test_a_batch_goes_on_past_bad_inputs_and_reports_each(files, capsys):
    batch_in = files / "batch"
    batch_in.mkdir()
    for name in ("good.png", "empty.png", "cut.png", "corrupt.png"):
        shutil.copy(files / name, batch_in / name)
    assert maptools_cli.main(["batch", str(batch_in), "-o", str(files / "maps"), "--kinds", "normal",
                              "--backend", "cpu"]) == 1
    out = capsys.readouterr().out
    rows = {line.split()[0].rsplit("/", 1)[-1]: line for line in out.splitlines() if "/batch/" in line}
    assert "ok" in rows["good.png"].split()
    for name, reason in (("empty.png", "empty file"), ("cut.png", "truncated PNG"),
                         ("corrupt.png", "cannot decode image")):
        assert "FAILED" in rows[name] and reason in rows[name], rows[name]
    assert "1 generated, 0 up to date, 3 failed" in out


def test_maptools_refuses_a_huge_declared_size_at_once(tmp_path, capsys):
    from tests.core.test_images import huge_npy

    src = huge_npy(tmp_path / "huge.npy")
    assert maptools_cli.main(["generate", "normal", str(src), "-o", str(tmp_path / "n.png"), "--backend", "cpu"]) == 2
    assert one_line(capsys, "maptools").startswith(f"maptools: error: {src}: 60000x60000 is larger than the limit")


def _loop(folder, a: str, b: str) -> None:
    (folder / a).symlink_to(folder / b)
    (folder / b).symlink_to(folder / a)


@pytest.mark.parametrize("material, key, value", [
    ('albedo = "loop.png"\nheight = "good.png"', "albedo", "loop.png"),
    ('albedo = "good.png"\nfolder = "loopdir"', "folder", "loopdir"),
    ('albedo = "good.png"\nheight = "good.png"\n[materials.m.maps]\ncone = "loop.png"', "maps.cone", "loop.png"),
])
def test_a_symbolic_link_loop_in_a_scene_path_is_one_line(files, capsys, material, key, value):
    _loop(files, "loop.png", "loop2.png")
    _loop(files, "loopdir", "loopdir2")
    path = files / "s.toml"
    path.write_text(material_scene(["basic"], material))
    assert cli.main(["render", str(path), "-o", str(files / "out.png"), "--size", "16x16"]) == 2
    line = one_line(capsys)
    assert f"{path}: materials.m.{key} = '{value}': symbolic link loop" in line, line


def test_a_symbolic_link_loop_as_the_material_folder_is_one_line(files, capsys):
    _loop(files, "loopdir", "loopdir2")
    assert cli.main(["render", "--material", str(files / "loopdir"), "-o", str(files / "out.png"), "--size", "16x16"]) == 2
    line = one_line(capsys)
    assert f"--material {files / 'loopdir'}: symbolic link loop" in line, line
