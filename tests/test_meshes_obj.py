"""OBJ files and mesh messages (wgpuviewer.meshes.obj, files, scene.limits): the text decoded before trimesh sees it
(UTF-16/32 and binary files named, Latin-1 names read), the face lines counted against the vertex limit before
trimesh parses, the file's material not read where the scene gives the object its own, symbolic link loops as one
line, a mesh too large for the camera blamed on its ``scale``, and the progress a load reports."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.test_meshes import mesh_scene, write_obj
from wgpuviewer import meshes
from wgpuviewer.core.errors import FileError, UserError
from wgpuviewer.meshes import files, obj
from wgpuviewer.scene import load_scene


@pytest.fixture(autouse=True)
def fresh_cache():
    meshes.clear_cache()
    yield
    meshes.clear_cache()


def scene_error(scene: Path, *parts: str) -> str:
    with pytest.raises(UserError) as error:
        load_scene(scene)
    message = str(error.value)
    assert "\n" not in message and message.startswith(f"{scene}: objects[0]."), message
    for part in parts:
        assert part in message, message
    return message


@pytest.mark.parametrize("encode, parts", [
    (lambda text: text.encode("utf-16"), ["text encoded as UTF-16", "save it as UTF-8"]),
    (lambda text: text.encode("utf-32"), ["text encoded as UTF-32"]),
    (lambda text: text.encode("utf-16-le"), ["UTF-16 text without a byte-order mark"]),
    (lambda text: b"\x00\x01\x02binary" + text.encode(), ["a binary file (a NUL byte at byte 0)"]),
])
def test_an_obj_in_another_encoding_is_named(tmp_path, encode, parts):
    path = write_obj(tmp_path)
    path.write_bytes(encode(path.read_text()))
    message = scene_error(mesh_scene(tmp_path, "panel.obj"), *parts)
    assert "charset_normalizer" not in message


def test_an_obj_with_latin1_names_and_a_bom_is_read(tmp_path):
    path = write_obj(tmp_path)
    path.write_bytes(b"\xef\xbb\xbf# caf\xe9 by an old exporter\n" + path.read_bytes())
    assert len(meshes.load_mesh(path).vertices) == 6


def test_face_lines_beyond_the_vertex_limit_are_refused_before_trimesh_parses(tmp_path, monkeypatch):
    import trimesh.exchange.obj

    def parse(*args, **kwargs):
        raise AssertionError("trimesh parsed a file the face count refuses")

    monkeypatch.setattr(meshes.model, "MAX_MESH_VERTICES", 20)
    monkeypatch.setattr(trimesh.exchange.obj, "load_obj", parse)
    path = tmp_path / "many.obj"
    path.write_text("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n" + "f 1/1 2/1 3/1\n" * 6 + "f\t1 2 3\n")
    with pytest.raises(FileError, match=r"24 vertices \(8 triangles\), more than the 20 a mesh may have"):
        meshes.load_mesh(path)
    assert obj.face_lines("f 1 2 3\nvt 0 0\nf\t1 2 3\n# f\nfoo f 1\nfo 1\n") == 2


def test_a_scene_material_means_the_files_material_is_not_read(tmp_path):
    write_obj(tmp_path)
    (tmp_path / "panel.mtl").unlink()
    scene = load_scene(mesh_scene(tmp_path, "panel.obj", material="bricks"))
    assert scene.objects[0].material == "bricks"
    meshes.clear_cache()
    scene_error(mesh_scene(tmp_path, "panel.obj"), "mtllib 'panel.mtl' not found")


def test_the_file_material_is_read_when_a_cached_mesh_lacks_it(tmp_path):
    path = write_obj(tmp_path)
    assert meshes.load_mesh(path, material=False).material is None
    assert meshes.load_mesh(path).material is not None
    assert meshes.load_mesh(path, material=False).material is not None  # the fuller entry serves both


def loop(folder: Path, *names: str) -> None:
    os.symlink(folder / names[1], folder / names[0])
    os.symlink(folder / names[0], folder / names[1])


def test_symbolic_link_loops_are_one_line(tmp_path):
    loop(tmp_path, "x.obj", "y.obj")
    scene_error(mesh_scene(tmp_path, "x.obj"), "objects[0].file = 'x.obj'", "symbolic link loop")
    sub = tmp_path / "sub"
    sub.mkdir()
    path = write_obj(sub)
    (sub / "panel.mtl").unlink()
    loop(sub, "panel.mtl", "other.mtl")
    scene_error(mesh_scene(sub, "panel.obj"), "mtllib 'panel.mtl'", "symbolic link loop")
    assert meshes.load_mesh(path, material=False).material is None


def test_a_mesh_too_large_for_the_camera_is_blamed_on_its_scale(tmp_path):
    write_obj(tmp_path)
    message = scene_error(mesh_scene(tmp_path, "panel.obj", "scale = 1e6"), "objects[0].scale = 1000000.0",
                          "measures [2e+06, 2e+06, 0]", "smaller scale")
    assert "size" not in message.split(":")[1]


def test_a_load_reports_its_progress(tmp_path, monkeypatch):
    seen = []

    class Progress:
        def __init__(self, what, unit):
            seen.append((what, unit))

        def __enter__(self):
            return lambda label, done, total: seen.append((label, done, total))

        def __exit__(self, *exc):
            return False

    monkeypatch.setattr(files, "terminal_progress", Progress)
    meshes.load_mesh(write_obj(tmp_path))
    assert seen == [("reading panel.obj", "step"), ("parsing", 0, 2), ("checking triangles", 1, 2), ("done", 2, 2)]
