"""Material folders as the free libraries ship them (folders generated here in each naming convention): ambientCG,
Poly Haven and generic names; the normal convention from the name (OpenGL preferred where both ship);
displacement read as height; 8/16-bit PNG and JPEG; ambiguities and unreadable files are one clear line."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.core.test_images import EXR_UINT, huge_exr
from wgpuviewer import cli, textures
from wgpuviewer.core.errors import FileError, InputError, UserError
from wgpuviewer.scene import default_scene_path, load_scene, with_folder_material
from wgpuviewer.scene.folders import FOLDER_SLOTS, FolderFiles, file_role, find_material_files

SIZE = 64


@pytest.fixture(autouse=True)
def _fresh_textures():
    textures.clear_cache()
    yield
    textures.clear_cache()


def relief():
    """A smooth tileable height field in [0, 1], its albedo and its OpenGL normals (green up), as arrays."""
    y, x = np.mgrid[0:SIZE, 0:SIZE] / SIZE
    height = 0.5 + 0.4 * np.sin(2 * np.pi * x) * np.cos(4 * np.pi * y)
    albedo = np.stack([0.3 + 0.5 * height, 0.4 * np.ones_like(height), 0.7 - 0.5 * height], -1)
    gy, gx = np.gradient(height * 4)
    n = np.stack([-gx, gy, np.ones_like(gx)], -1)  # +y towards row 0: OpenGL's green up
    return height, albedo, n / np.linalg.norm(n, axis=-1, keepdims=True)


def write(path, rgb_or_grey, bits=8):
    top = 255 if bits == 8 else 65535
    data = np.clip(np.rint(np.asarray(rgb_or_grey) * top), 0, top).astype(np.uint8 if bits == 8 else np.uint16)
    if data.ndim == 3:
        data = data[..., ::-1]  # OpenCV writes BGR
    assert cv2.imwrite(str(path), data)


def make_folder(root, convention: str):
    height, albedo, normal = relief()
    gl, dx = normal * 0.5 + 0.5, normal * [0.5, -0.5, 0.5] + 0.5
    folder = root / convention
    folder.mkdir()
    if convention == "ambientcg":
        base = "Rock042_1K-PNG"
        write(folder / f"{base}_Color.png", albedo)
        write(folder / f"{base}_NormalGL.png", gl)
        write(folder / f"{base}_NormalDX.png", dx)
        write(folder / f"{base}_Displacement.png", height, bits=16)
        write(folder / f"{base}_Roughness.png", height)
        write(folder / f"{base}_AmbientOcclusion.png", height)
        write(folder / "Rock042.png", albedo)  # the preview
        (folder / f"{base}.usdc").write_bytes(b"not an image")
    elif convention == "polyhaven":
        write(folder / "rock_wall_diff_1k.jpg", albedo)
        write(folder / "rock_wall_nor_dx_1k.png", dx)
        write(folder / "rock_wall_disp_1k.png", height, bits=16)
        write(folder / "rock_wall_rough_1k.jpg", height)
        write(folder / "rock_wall_arm_1k.jpg", albedo)
    else:
        write(folder / "BaseColor.jpg", albedo)
        write(folder / "normal.png", gl, bits=16)
        write(folder / "bump.png", height)
    return folder


#: The default scene's lines naming its bricks material's albedo and height.
BRICKS_ALBEDO = 'albedo = { builtin = "bricks", size = [512, 512] }'
BRICKS_HEIGHT = 'height = { builtin = "bricks", size = [512, 512] }'


def folder_scene(tmp_path, albedo: str, height: str = BRICKS_HEIGHT) -> tuple[Path, str]:
    """The default scene as ``tmp_path/s.toml`` (path, text) with its bricks material's albedo line replaced by
    ``albedo`` (a ``folder = ...`` line) and its height line by ``height``."""
    text = default_scene_path().read_text().replace(BRICKS_ALBEDO, albedo).replace(BRICKS_HEIGHT, height)
    path = tmp_path / "s.toml"
    path.write_text(text)
    return path, text


EXPECTED = {
    "ambientcg": ("Rock042_1K-PNG_Color.png", "Rock042_1K-PNG_NormalGL.png", "opengl",
                  "Rock042_1K-PNG_Displacement.png"),
    "polyhaven": ("rock_wall_diff_1k.jpg", "rock_wall_nor_dx_1k.png", "directx", "rock_wall_disp_1k.png"),
    "generic": ("BaseColor.jpg", "normal.png", "opengl", "bump.png"),
}


@pytest.mark.parametrize("convention", list(EXPECTED))
def test_each_naming_convention_is_recognised(tmp_path, convention):
    found = find_material_files(make_folder(tmp_path, convention))
    albedo, normal, normal_y, height = EXPECTED[convention]
    assert (found.albedo.name, found.normal.name, found.normal_y, found.height.name) == \
        (albedo, normal, normal_y, height)


@pytest.mark.parametrize("name,role", [
    ("wood_floor_nor_gl_2k.exr", ("normal", "opengl")), ("Metal_NormalDX.jpg", ("normal", "directx")),
    ("brick-normal-directx.png", ("normal", "directx")), ("tiles_Height.tif", ("height", "")),
    ("sand_displacement.npy", ("height", "")), ("albedo.png", ("albedo", "")), ("Diffuse_1k.jpg", ("albedo", "")),
    ("base_color.png", ("albedo", "")), ("Rock_Roughness.png", None), ("rock_ao_1k.jpg", None),
    ("preview.png", None), ("notes_Color.txt", None),
])
def test_file_roles_by_name(name, role):
    assert file_role(Path(name)) == role


def test_a_scene_material_from_a_folder_and_keys_that_override_it(tmp_path):
    make_folder(tmp_path, "ambientcg")
    write(tmp_path / "other_height.png", relief()[0][::-1])
    scene_path, text = folder_scene(tmp_path, 'folder = "ambientcg"', height="")
    material = load_scene(scene_path).materials["bricks"]
    assert material.albedo.path.name == "Rock042_1K-PNG_Color.png"
    assert material.normal.path.name == "Rock042_1K-PNG_NormalGL.png" and material.normal_y == "opengl"
    assert material.height.path.name == "Rock042_1K-PNG_Displacement.png" and not material.height_is_depth
    assert material.height_scale == 0.06 and material.uv_scale == (2.0, 2.0)  # the table's own keys stay
    height = textures.load_height(material.height)
    assert np.abs(height - relief()[0]).max() < 1e-4  # 16-bit displacement read as height
    scene_path.write_text(text.replace('folder = "ambientcg"', 'folder = "ambientcg"\nheight = "other_height.png"'))
    assert load_scene(scene_path).materials["bricks"].height.path.name == "other_height.png"


def test_ambiguous_and_empty_folders_are_clear_errors(tmp_path):
    folder = make_folder(tmp_path, "ambientcg")
    write(folder / "Rock042_2K-PNG_Color.png", relief()[1])
    with pytest.raises(FileError, match="2 candidates for the albedo: Rock042_1K-PNG_Color.png, "
                                        "Rock042_2K-PNG_Color.png; keep one"):
        find_material_files(folder)
    (tmp_path / "nothing").mkdir()
    (tmp_path / "nothing" / "readme.txt").write_text("hi")
    with pytest.raises(FileError, match="no albedo, normal or height file recognised by name"):
        find_material_files(tmp_path / "nothing")
    scene_path, _ = folder_scene(tmp_path, 'folder = "ambientcg"')
    with pytest.raises(UserError) as error:
        load_scene(scene_path)
    assert str(error.value).startswith(f"{scene_path}: materials.bricks.folder = 'ambientcg': 2 candidates")


def test_a_file_the_reader_cannot_read_is_named_with_the_folder_key(tmp_path):
    folder = make_folder(tmp_path, "polyhaven")
    (folder / "rock_wall_disp_1k.png").unlink()
    huge_exr(folder / "rock_wall_disp_1k.exr", SIZE, SIZE, channels=(("Y", EXR_UINT, 1),))  # an integer channel
    with pytest.raises(UserError, match=r"--material .*polyhaven: rock_wall_disp_1k.exr: EXR channel 'Y' holds UINT "
                                        r"values; expected HALF or FLOAT"):
        with_folder_material(load_scene(default_scene_path()), folder)


def test_render_material_shows_the_folder_on_the_default_scene_plane(tmp_path, capsys, adapter):
    """OpenGL and DirectX normal maps of the same relief render alike (the convention comes from the name)."""
    outs = {}
    for convention in ("ambientcg", "polyhaven"):
        outs[convention] = tmp_path / f"{convention}.png"
        assert cli.main(["render", "--material", str(make_folder(tmp_path, convention)), "-o",
                         str(outs[convention]), "--size", "96x64", "--technique", "normal"]) == 0
    gl, dx = (cv2.imread(str(outs[c])).astype(int) for c in ("ambientcg", "polyhaven"))
    plain = tmp_path / "plain.png"
    assert cli.main(["render", "-o", str(plain), "--size", "96x64", "--technique", "normal"]) == 0
    assert np.abs(gl - cv2.imread(str(plain)).astype(int)).mean() > 5  # the plane shows the folder's material
    # albedo JPEG vs PNG differs a little; the normals' convention would differ a lot
    assert np.abs(gl - dx).mean() < 3, np.abs(gl - dx).mean()
    flipped = make_folder(tmp_path, "generic")  # OpenGL by name, but DirectX content: visibly different
    write(flipped / "normal.png", relief()[2] * [0.5, -0.5, 0.5] + 0.5)
    assert cli.main(["render", "--material", str(flipped), "-o", str(tmp_path / "f.png"), "--size", "96x64",
                     "--technique", "normal"]) == 0
    assert np.abs(cv2.imread(str(tmp_path / "f.png")).astype(int) - gl).mean() > np.abs(gl - dx).mean() + 1


def test_view_material_without_a_display_renders_it(tmp_path, monkeypatch, capsys, adapter):
    monkeypatch.setenv("DISPLAY", "")
    monkeypatch.setenv("WAYLAND_DISPLAY", "")
    monkeypatch.chdir(tmp_path)
    assert cli.main(["view", "--material", str(make_folder(tmp_path, "generic")), "--technique", "basic",
                     "--size", "64x48"]) == 0
    assert (tmp_path / "out" / "default_basic.png").is_file()
    assert cli.main(["view", "--material", str(tmp_path / "missing")]) == 2
    assert f"--material {tmp_path / 'missing'}: folder not found" in capsys.readouterr().err


def test_keys_next_to_a_folder_win_over_its_files_for_their_slots(tmp_path):
    """The folder is not searched for a slot the scene names: two height candidates, or a broken height link, do
    not matter when the scene gives the height (or depth) itself."""
    folder = make_folder(tmp_path, "generic")
    write(folder / "height.png", relief()[0])  # a second height candidate next to bump.png
    write(tmp_path / "mine.png", relief()[0][::-1])
    with pytest.raises(FileError, match="2 candidates for the height: bump.png, height.png"):
        find_material_files(folder)
    found = find_material_files(folder, named={"height"})
    assert (found.albedo.name, found.normal.name, found.height) == ("BaseColor.jpg", "normal.png", None)
    assert find_material_files(folder, named=FOLDER_SLOTS) == FolderFiles(None, None, "opengl", None)
    with pytest.raises(InputError, match="named \\['depth'\\]: expected slots among albedo, normal, height"):
        find_material_files(folder, named={"depth"})
    scene_path, text = folder_scene(tmp_path, 'folder = "generic"', height='height = "mine.png"')
    material = load_scene(scene_path).materials["bricks"]
    assert material.height.path.name == "mine.png" and material.albedo.path.name == "BaseColor.jpg"
    scene_path.write_text(text.replace('height = "mine.png"', 'depth = "mine.png"'))
    material = load_scene(scene_path).materials["bricks"]
    assert material.height.path.name == "mine.png" and material.height_is_depth
    (folder / "bump.png").unlink()
    (folder / "height.png").unlink()
    (folder / "height.png").symlink_to("gone.png")
    assert find_material_files(folder, named={"height"}).height is None
    with pytest.raises(FileError, match="broken link"):
        find_material_files(folder)


@pytest.mark.parametrize("case", ["dangling", "loop", "self loop", "folder"])
def test_an_unusable_entry_named_for_a_slot_is_an_error_naming_it(tmp_path, capsys, case):
    """It used to be dropped: a dangling height link rendered a flat surface with exit 0, and a folder of broken
    links was "no albedo, normal or height file recognised"."""
    folder = make_folder(tmp_path, "generic")
    (folder / "bump.png").unlink()
    bad = folder / "height.png"
    if case == "dangling":
        bad.symlink_to("missing.png")
        reason = "height.png: broken link to missing.png (the target does not exist); fix or remove the link"
    elif case == "loop":
        (folder / "other.png").symlink_to("height.png")
        bad.symlink_to("other.png")
        reason = "height.png: symbolic link loop"
    elif case == "self loop":
        bad.symlink_to("height.png")
        reason = "height.png: symbolic link loop"
    else:
        bad.mkdir()
        reason = "height.png: a folder, not an image file"
    with pytest.raises(FileError) as error:
        find_material_files(folder)
    assert error.value.reason.startswith(reason), error.value.reason
    out = tmp_path / "x.png"
    assert cli.main(["render", "--material", str(folder), "-o", str(out), "--size", "16x16",
                     "--technique", "basic"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"wgpuviewer: error: --material {folder}: {error.value.reason}"], err
    assert not out.exists()
    for name in ("BaseColor.jpg", "normal.png"):  # a folder of nothing but broken links names them too
        (folder / name).unlink()
    (folder / "albedo.png").symlink_to("nowhere.png")
    with pytest.raises(FileError, match="albedo.png: broken link to nowhere.png"):
        find_material_files(folder)


def test_maps_maptools_batch_wrote_into_the_folder_are_not_the_sets_textures(tmp_path, capsys):
    """A batch run on the displacement with the folder as output puts X_Displacement.normal.png (a normal map by
    name), .complexity.png and .cone.png (height maps by name) next to the set: each has its record, so the scan
    takes the set's own files, and an output whose record is gone is a candidate again."""
    from maptools import cli as maptools_cli

    folder = make_folder(tmp_path, "ambientcg")
    displacement = folder / "Rock042_1K-PNG_Displacement.png"
    assert maptools_cli.main(["batch", str(displacement), "-o", str(folder), "--kinds", "normal,complexity,cone",
                              "--backend", "cpu"]) == 0
    outputs = sorted(p.name for p in folder.glob("*_Displacement.*.*") if p.suffix != ".json")
    assert outputs == ["Rock042_1K-PNG_Displacement.complexity.png", "Rock042_1K-PNG_Displacement.cone.npy",
                       "Rock042_1K-PNG_Displacement.normal.png"]
    found = find_material_files(folder)
    assert (found.albedo.name, found.normal.name, found.normal_y, found.height.name) == EXPECTED["ambientcg"]
    material = with_folder_material(load_scene(default_scene_path()), folder).materials["folder ambientcg"]
    assert (material.normal.path, material.height.path) == (folder / "Rock042_1K-PNG_NormalGL.png", displacement)
    (folder / "Rock042_1K-PNG_Displacement.normal.png.json").unlink()
    with pytest.raises(FileError, match="2 candidates for the normal: Rock042_1K-PNG_Displacement.normal.png, "
                                        "Rock042_1K-PNG_NormalGL.png"):
        find_material_files(folder)
