"""`--material DIR` and a scene's `folder =` say in one line what they picked for each slot and what they left out,
and why; once per folder, through the wgpuviewer.scene logger the CLIs print."""

from __future__ import annotations

import json
import logging

import numpy as np

from maptools import VERSION
from tests.relief.scenes import material_scene
from tests.test_material_folders import make_folder, write
from wgpuviewer import cli
from wgpuviewer.scene import default_scene_path, load_scene, with_folder_material


def _lines(caplog) -> list[str]:
    """The scene's notes (INFO records) so far."""
    return [r.getMessage() for r in caplog.records if r.name == "wgpuviewer.scene"]


def _with_batch_output(folder):
    """An ambientCG folder with a normal map maptools batch wrote next to the textures, and its record."""
    out = folder / "Rock042_1K-PNG_Displacement.normal.png"
    write(out, np.full((8, 8, 3), 0.5))
    (folder / f"{out.name}.json").write_text(json.dumps({"version": VERSION}))
    return folder


def test_material_says_what_it_picked_and_what_it_left_out(tmp_path, caplog):
    caplog.set_level(logging.INFO, "wgpuviewer")
    folder = _with_batch_output(make_folder(tmp_path, "ambientcg"))
    scene = load_scene(default_scene_path())
    with_folder_material(scene, folder)
    with_folder_material(scene, folder)  # once per folder
    base = "Rock042_1K-PNG"
    assert _lines(caplog) == [
        f"--material {folder}: picked albedo {base}_Color.png, normal {base}_NormalGL.png (OpenGL), height "
        f"{base}_Displacement.png; ignored Rock042.png, {base}_AmbientOcclusion.png, {base}_Roughness.png (no "
        f"albedo, normal or height in its name); {base}.usdc, {base}_Displacement.normal.png.json (not an image "
        f"file); {base}_Displacement.normal.png (written by maptools batch); {base}_NormalDX.png (DirectX normal "
        "map; the OpenGL one is used)"]


def test_a_scene_folder_names_its_key_and_the_slots_the_scene_gives(tmp_path, caplog):
    caplog.set_level(logging.INFO, "wgpuviewer")
    folder = make_folder(tmp_path, "polyhaven")
    (folder / "unused").mkdir()
    scene = tmp_path / "s.toml"
    scene.write_text(material_scene(["basic"], 'folder = "polyhaven"\nheight = "builtin:bumps"'))
    load_scene(scene)
    [line] = _lines(caplog)
    assert line == (f"{scene}: materials.m.folder = 'polyhaven': picked albedo rock_wall_diff_1k.jpg, normal "
                    "rock_wall_nor_dx_1k.png (DirectX), height from the scene; ignored rock_wall_arm_1k.jpg, "
                    "rock_wall_rough_1k.jpg (no albedo, normal or height in its name); rock_wall_disp_1k.png (the "
                    "scene gives the height); unused (a folder)")


def test_the_cli_prints_the_line_once_on_stderr(tmp_path, capsys, adapter):
    folder = make_folder(tmp_path, "generic")
    out = tmp_path / "r.png"
    assert cli.main(["render", "--material", str(folder), "-o", str(out), "--size", "16x16",
                     "--technique", "basic"]) == 0
    captured = capsys.readouterr()
    assert captured.out.strip() == str(out)
    ours = [line for line in captured.err.splitlines() if line.startswith("wgpuviewer:")]  # not the adapter notice
    assert ours == [
        f"wgpuviewer: --material {folder}: picked albedo BaseColor.jpg, normal normal.png (OpenGL), "
        "height bump.png; nothing else in the folder"]
