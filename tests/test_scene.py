"""Scene files: the shipped scenes parse as intended, and every kind of mistake is a one-line
UserError naming the file, the key path and the offending value."""

import dataclasses
from pathlib import Path

import cv2
import numpy as np
import pytest

from wgpuviewer.core.errors import UserError
from wgpuviewer.meshes import DEFAULT_SIZES, build
from wgpuviewer.scene import Scene, default_scene_path, load_scene, parse_scene
from wgpuviewer.scene.model import DEFAULT_LIGHT
from wgpuviewer.techniques import TECHNIQUES
from wgpuviewer.textures import TextureRef

SCENES = Path(__file__).resolve().parent.parent / "scenes"

CAMERA = """
[camera]
position = [0.0, 1.0, 3.0]
target = [0.0, 0.0, 0.0]
"""
MATERIAL = """
[materials.rock]
albedo = [0.5, 0.4, 0.3]
"""
OBJECT = """
[[objects]]
type = "plane"
material = "rock"
size = [2.0, 2.0]
"""


def scene_text(head="", camera=CAMERA, material=MATERIAL, objects=OBJECT, tail="") -> str:
    """A valid minimal scene, with sections replaced or text added before/after."""
    return "\n".join((head, camera, material, objects, tail))


def write(tmp_path: Path, text: str, name: str = "x.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def load(tmp_path: Path, text: str) -> Scene:
    return load_scene(write(tmp_path, text))


def error(tmp_path: Path, text: str, *parts: str) -> str:
    """Load ``text`` as a scene file, expect a UserError naming the file and all ``parts``."""
    path = write(tmp_path, text)
    with pytest.raises(UserError) as e:
        load_scene(path)
    msg = str(e.value)
    assert "\n" not in msg, msg
    assert msg.startswith(f"{path}: "), msg
    for part in parts:
        assert part in msg, f"{part!r} not in {msg!r}"
    return msg


# --- shipped scenes ----------------------------------------------------------------------------


def test_default_scene():
    scene = load_scene(default_scene_path())
    assert default_scene_path().read_bytes() == (SCENES / "default.toml").read_bytes()
    assert scene.techniques == ("basic", "normal", "parallax", "steep", "pom", "pom_adaptive", "relief", "maxmip")
    assert scene.technique == "pom"
    assert scene.technique_params["pom"] == {"layers": 32}
    assert scene.technique_params["steep"] == {"layers": 32}
    assert scene.technique_params["parallax"] == TECHNIQUES["parallax"].defaults()
    assert set(scene.technique_params) == set(scene.techniques)
    bricks = scene.materials["bricks"]
    assert bricks.height == TextureRef("builtin", name="bricks", size=(512, 512))
    assert bricks.albedo == bricks.height and bricks.normal is None and not bricks.height_is_depth
    assert bricks.uv_scale == (2.0, 2.0) and 0.04 <= bricks.height_scale <= 0.08
    plane = scene.objects[0]
    assert (plane.type, plane.material, plane.size) == ("plane", "bricks", (4.0, 4.0))
    assert {o.type for o in scene.objects} == {"plane", "box"}
    assert {light.type for light in scene.lights} == {"directional", "point"}
    direction = next(light.direction for light in scene.lights if light.type == "directional")
    assert abs(np.linalg.norm(direction) - 1) < 1e-9
    cam = scene.camera
    assert cam.position[1] > 0.5 and cam.fov == 55.0 and 0 < cam.near < cam.far
    all_refs = [r for m in scene.materials.values() for r in (m.albedo, m.normal, m.height) if r]
    assert all(r.kind == "builtin" for r in all_refs)


def test_normal_only_scene():
    scene = load_scene(SCENES / "normal_only.toml")
    assert scene.techniques == ("normal",) and scene.technique == "normal"
    assert scene.technique_params == {"normal": {}}


def test_hard_cases_scene():
    scene = load_scene(SCENES / "hard_cases.toml")
    names = {m.height.name for m in scene.materials.values()}
    assert names == {"flat0", "flat1", "spike", "step", "wall", "checker"}
    assert len(scene.objects) == 6


# --- defaults and resolution -------------------------------------------------------------------


def test_minimal_scene_defaults(tmp_path):
    scene = load(tmp_path, scene_text())
    assert scene.name == "x" and scene.path == (tmp_path / "x.toml").resolve()
    assert scene.techniques == tuple(TECHNIQUES) and scene.technique == next(iter(TECHNIQUES))
    assert scene.technique_params == {name: t.defaults() for name, t in TECHNIQUES.items()}
    assert scene.lights == (DEFAULT_LIGHT,)
    assert scene.background == (0.02, 0.02, 0.03)
    cam = scene.camera
    assert (cam.up, cam.fov, cam.near, cam.far) == ((0.0, 1.0, 0.0), 60.0, 0.05, 100.0)
    rock = scene.materials["rock"]
    assert rock.albedo == TextureRef("color", color=(0.5, 0.4, 0.3))
    assert (rock.normal, rock.height, rock.normal_y, rock.height_scale, rock.uv_scale) == (
        None, None, "opengl", 0.05, (1.0, 1.0))
    assert (rock.shadows, rock.depth_offset, rock.address) == ("off", False, "repeat")
    assert scene.objects[0].position == (0.0, 0.0, 0.0) and scene.objects[0].rotation == (0.0, 0.0, 0.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        scene.name = "other"


def test_technique_defaults_to_first_listed(tmp_path):
    scene = load(tmp_path, scene_text('[scene]\ntechniques = ["steep", "basic"]'))
    assert scene.technique == "steep" and set(scene.technique_params) == {"steep", "basic"}


def test_relative_paths_resolve_against_scene_file(tmp_path, monkeypatch):
    (tmp_path / "textures").mkdir()
    assert cv2.imwrite(str(tmp_path / "textures" / "h.png"), np.zeros((4, 4), np.uint8))
    assert cv2.imwrite(str(tmp_path / "n.png"), np.full((4, 4, 3), 128, np.uint8))
    material = '[materials.rock]\nalbedo = "builtin:bricks"\nheight = "textures/h.png"\nnormal = "n.png"\n'
    path = write(tmp_path, scene_text(material=material))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    rock = load_scene(path).materials["rock"]
    assert rock.height == TextureRef("file", path=(tmp_path / "textures" / "h.png").resolve())
    assert rock.normal.path == (tmp_path / "n.png").resolve()
    # Also when the scene path itself is relative.
    assert load_scene(Path("..") / "x.toml").materials["rock"].height.path == rock.height.path


def test_no_path_resolves_against_cwd(tmp_path, monkeypatch):
    np.save(tmp_path / "h.npy", np.zeros((2, 2), np.float32))
    monkeypatch.chdir(tmp_path)
    scene = parse_scene(scene_text(material=MATERIAL + 'height = "h.npy"\n'))
    assert scene.path is None and scene.name == "scene"
    assert scene.materials["rock"].height.path == (tmp_path / "h.npy").resolve()


def test_absolute_path(tmp_path):
    np.save(tmp_path / "h.npy", np.zeros((2, 2), np.float32))
    text = scene_text(material=MATERIAL + f"height = '{(tmp_path / 'h.npy').as_posix()}'\n")
    assert load(tmp_path, text).materials["rock"].height.path == (tmp_path / "h.npy").resolve()


def test_depth_channel_and_builtin_size(tmp_path):
    assert cv2.imwrite(str(tmp_path / "d.png"), np.zeros((4, 4, 3), np.uint8))
    material = (
        "[materials.rock]\nalbedo = { builtin = 'bumps', size = [64, 32] }\n"
        "depth = 'd.png'\nchannel = 'g'\nnormal_y = 'opengl'\nheight_scale = 0.1\nuv_scale = [3, 1.5]\n"
    )
    rock = load(tmp_path, scene_text(material=material)).materials["rock"]
    assert rock.albedo == TextureRef("builtin", name="bumps", size=(64, 32))
    assert rock.height_is_depth and rock.height.channel == "g" and rock.height.kind == "file"
    assert rock.height_scale == 0.1 and rock.uv_scale == (3.0, 1.5)


def test_lights_and_objects(tmp_path):
    tail = """
[[lights]]
type = "directional"
direction = [0, -2, 0]
[[lights]]
type = "point"
position = [1, 2, 3]
color = [1, 0.5, 0]
intensity = 3
[[objects]]
type = "box"
material = "rock"
size = [1, 2, 3]
position = [0, 1, 0]
rotation = [0, 45, 0]
[[objects]]
type = "quad"
material = "rock"
size = [1, 1]
"""
    scene = load(tmp_path, scene_text(tail=tail))
    sun, lamp = scene.lights
    assert sun.direction == (0.0, -1.0, 0.0) and sun.position is None
    assert lamp.position == (1.0, 2.0, 3.0) and lamp.color == (1.0, 0.5, 0.0) and lamp.intensity == 3.0
    assert [o.type for o in scene.objects] == ["plane", "box", "quad"]
    assert scene.objects[1].size == (1.0, 2.0, 3.0) and scene.objects[1].rotation == (0.0, 45.0, 0.0)


# --- errors ------------------------------------------------------------------------------------


def test_toml_syntax_error(tmp_path):
    error(tmp_path, "[camera]\nposition = [0, 1\ntarget = [0, 0, 0]\n", "TOML syntax error", "line 3, column")


def test_unknown_top_level_key(tmp_path):
    error(tmp_path, scene_text("colour = 1"), "colour = 1", "unknown key", "allowed: scene, camera, lights")


@pytest.mark.parametrize("text,parts", [
    (scene_text(camera=CAMERA + "fovy = 50\n"), ["camera.fovy = 50", "unknown key", "position, target, up, fov"]),
    (scene_text("[scene]\ntitle = 'x'"), ["scene.title = 'x'", "allowed: name, technique, techniques"]),
    (scene_text(material=MATERIAL + "roughness = 0.5\n"), ["materials.rock.roughness = 0.5", "albedo, normal"]),
    (scene_text(objects=OBJECT + "scale = 2\n"), ["objects[0].scale = 2", "not used by a plane object",
                                                   'only type = "mesh" objects take file, node and scale']),
    (scene_text(objects=OBJECT + "colour = 2\n"), ["objects[0].colour = 2", "type, material, size"]),
    (scene_text(tail="[[lights]]\ntype = 'point'\nposition = [0, 1, 0]\nradius = 1\n"),
     ["lights[0].radius = 1", "unknown key"]),
    (scene_text(material="[materials.rock]\nalbedo = { builtin = 'bricks', sise = [4, 4] }\n"),
     ["materials.rock.albedo.sise = [4, 4]", "allowed: builtin, size"]),
])
def test_unknown_nested_keys(tmp_path, text, parts):
    error(tmp_path, text, *parts)


@pytest.mark.parametrize("text,parts", [
    (scene_text(camera=CAMERA + "fov = 'wide'\n"), ["camera.fov = 'wide'", "expected a number"]),
    (scene_text(camera=CAMERA + "fov = true\n"), ["camera.fov = True", "expected a number"]),
    (scene_text(camera="camera = 5\n"), ["camera = 5", "expected a table"]),
    (scene_text(camera="[camera]\nposition = [0, 1]\ntarget = [0, 0, 0]\n"),
     ["camera.position = [0, 1]", "expected an array of 3 numbers"]),
    (scene_text("[scene]\nname = 3"), ["scene.name = 3", "expected a string"]),
    (scene_text("lights = 3"), ["lights = 3", "expected an array of tables ([[lights]])"]),
    (scene_text(material=MATERIAL + "height = 5\n"), ["materials.rock.height = 5", "expected a texture"]),
    (scene_text(material=MATERIAL + "height = [0.5, 0.5, 0.5]\n"), ["materials.rock.height = [0.5, 0.5, 0.5]"]),
    (scene_text(material="[materials.rock]\nalbedo = { builtin = 'bricks', size = [4.5, 4] }\n"),
     ["materials.rock.albedo.size = [4.5, 4]", "integers"]),
    (scene_text(objects=OBJECT.replace('"plane"', '"cone"')),
     ["objects[0].type = 'cone'", "plane, quad, box, sphere, cylinder, torus, mesh"]),
    (scene_text(objects=OBJECT.replace('"plane"', '"sphere"')), ["objects[0].size = [2.0, 2.0]", "array of 1 numbers"]),
    (scene_text(material=MATERIAL + "normal_y = 'up'\n"), ["materials.rock.normal_y = 'up'", "opengl, directx"]),
    (scene_text(material=MATERIAL + "shadows = 'sharp'\n"), ["materials.rock.shadows = 'sharp'", "off, hard, soft"]),
    (scene_text(material=MATERIAL + "depth_offset = 1\n"), ["materials.rock.depth_offset = 1", "true or false"]),
    (scene_text(material=MATERIAL + "address = 'mirror'\n"), ["materials.rock.address = 'mirror'", "repeat, clamp"]),
    (scene_text("[scene]\ntechniques = 'pom'"), ["scene.techniques = 'pom'", "array of technique names"]),
    (scene_text(tail="[techniques]\npom = 3\n"), ["techniques.pom = 3", "expected a table"]),
    (scene_text(tail="[techniques.steep]\nlayers = 8.5\n"), ["techniques.steep.layers = 8.5", "integer"]),
])
def test_wrong_types(tmp_path, text, parts):
    error(tmp_path, text, *parts)


@pytest.mark.parametrize("text,parts", [
    (scene_text(camera=CAMERA + "fov = 200\n"), ["camera.fov = 200: out of range, expected 1 to 179"]),
    (scene_text(camera=CAMERA + "fov = 1\n"), ["camera.fov = 1: out of range"]),
    (scene_text(camera=CAMERA + "near = 0\n"), ["camera.near = 0: out of range, expected > 0"]),
    (scene_text(camera=CAMERA + "near = 2\nfar = 1\n"), ["camera.far = 1", "more than camera.near (2)"]),
    (scene_text(material=MATERIAL + "height_scale = 1.5\n"), ["materials.rock.height_scale = 1.5", "0 to 1"]),
    (scene_text(material=MATERIAL + "uv_scale = [1, 0]\n"), ["materials.rock.uv_scale = [1, 0]", "> 0"]),
    (scene_text(material="[materials.rock]\nalbedo = [1.2, 0, 0]\n"),
     ["materials.rock.albedo = [1.2, 0, 0]", "0 to 1"]),
    (scene_text(objects=OBJECT.replace("[2.0, 2.0]", "[2.0, -1.0]")), ["objects[0].size = [2.0, -1.0]", "> 0"]),
    (scene_text("[scene]\nbackground = [0, 0, 2]"), ["scene.background = [0, 0, 2]", "0 to 1"]),
    (scene_text(tail="[[lights]]\ntype = 'point'\nposition = [0, 1, 0]\nintensity = -1\n"),
     ["lights[0].intensity = -1", ">= 0"]),
    (scene_text(material="[materials.rock]\nalbedo = { builtin = 'bricks', size = [0, 4] }\n"),
     ["materials.rock.albedo.size = [0, 4]", "1 to 8192"]),
    (scene_text(tail="[techniques.pom]\nlayers = 0\n"), ["techniques.pom.layers = 0: out of range"]),
])
def test_out_of_range(tmp_path, text, parts):
    error(tmp_path, text, *parts)


@pytest.mark.parametrize("text,parts", [
    (scene_text(camera="[camera]\ntarget = [0, 0, 0]\n"), ["camera.position: missing required key"]),
    (scene_text(camera=""), ["camera: missing required key", "[camera]"]),
    (scene_text(objects=""), ["objects: missing required key", "at least one [[objects]]"]),
    (scene_text("objects = []", objects=""), ["objects = []: expected at least one [[objects]]"]),
    (scene_text(objects="[[objects]]\nmaterial = 'rock'\nsize = [1, 1]\n"), ["objects[0].type: missing required key"]),
    (scene_text(material="[materials.rock]\nheight = 'builtin:bumps'\n"),
     ["materials.rock.albedo: missing required key"]),
    (scene_text(tail="[[lights]]\ntype = 'directional'\n"), ["lights[0].direction: missing required key"]),
    (scene_text(tail="[[lights]]\ndirection = [0, -1, 0]\n"), ["lights[0].type: missing required key"]),
])
def test_missing_required(tmp_path, text, parts):
    error(tmp_path, text, *parts)


def test_builtin_shapes_without_a_size_get_their_default(tmp_path):
    objects = "".join(f"[[objects]]\ntype = '{kind}'\nmaterial = 'rock'\n" for kind in DEFAULT_SIZES)
    scene = load_scene(write(tmp_path, scene_text(objects=objects)))
    assert [o.size for o in scene.objects] == list(DEFAULT_SIZES.values())
    for obj in scene.objects:  # each default fills a cube of side 1 around the origin
        reach = np.abs(build(obj.type, obj.size)[:, :3]).max(axis=0)
        assert np.isclose(reach.max(), 0.5, atol=1e-6), (obj.type, reach)


def test_missing_file(tmp_path):
    msg = error(tmp_path, scene_text(material=MATERIAL + "height = 'rock.png'\n"),
                "materials.rock.height = 'rock.png': file not found", str((tmp_path / "rock.png").resolve()))
    assert msg.endswith(f"(looked for {(tmp_path / 'rock.png').resolve()})")


def test_texture_path_is_a_folder(tmp_path):
    (tmp_path / "maps").mkdir()
    error(tmp_path, scene_text(material=MATERIAL + "height = 'maps'\n"), "materials.rock.height = 'maps'", "is a directory")


@pytest.mark.parametrize("value,shown", [("'builtin:brick'", "'builtin:brick'"), ("{ builtin = 'brick' }", "'brick'")])
def test_unknown_builtin(tmp_path, value, shown):
    error(tmp_path, scene_text(material=MATERIAL + f"height = {value}\n"),
          shown, "unknown builtin texture", "bricks, bumps, ridges, flat0")


@pytest.mark.parametrize("head,parts", [
    ('[scene]\ntechniques = ["pom", "nope"]', ["scene.techniques[1] = 'nope'", "unknown technique", "basic, normal"]),
    ('[scene]\ntechnique = "nope"', ["scene.technique = 'nope'", "unknown technique"]),
])
def test_unknown_technique(tmp_path, head, parts):
    error(tmp_path, scene_text(head), *parts)


def test_unknown_technique_section(tmp_path):
    error(tmp_path, scene_text(tail="[techniques.nope]\nlayers = 3\n"), "techniques.nope", "unknown technique")


def test_technique_section_not_listed(tmp_path):
    error(tmp_path, scene_text('[scene]\ntechniques = ["basic"]', tail="[techniques.pom]\nlayers = 8\n"),
          "techniques.pom = {'layers': 8}", "not in scene.techniques (basic)")


def test_unknown_technique_parameter(tmp_path):
    error(tmp_path, scene_text(tail="[techniques.pom]\nlayer = 8\n"),
          "techniques.pom.layer = 8", "unknown key; allowed: layers")
    error(tmp_path, scene_text(tail="[techniques.basic]\nlayers = 8\n"),
          "techniques.basic.layers = 8", "unknown key; allowed: none")


def test_default_technique_not_listed(tmp_path):
    error(tmp_path, scene_text('[scene]\ntechniques = ["basic", "normal"]\ntechnique = "pom"'),
          "scene.technique = 'pom'", "not in scene.techniques (basic, normal)")


def test_duplicate_technique(tmp_path):
    error(tmp_path, scene_text('[scene]\ntechniques = ["pom", "basic", "pom"]'),
          "scene.techniques = ['pom', 'basic', 'pom']", "'pom' listed twice")


def test_empty_technique_list(tmp_path):
    error(tmp_path, scene_text("[scene]\ntechniques = []"), "scene.techniques = []", "non-empty")


def test_unknown_material(tmp_path):
    error(tmp_path, scene_text(objects=OBJECT.replace('"rock"', '"rok"')),
          "objects[0].material = 'rok'", "unknown material; defined: rock")


def test_height_and_depth(tmp_path):
    error(tmp_path, scene_text(material=MATERIAL + "height = 'builtin:bumps'\ndepth = 'builtin:bumps'\n"),
          "materials.rock.depth = 'builtin:bumps'", "both height and depth")


@pytest.mark.parametrize("text,parts", [
    (scene_text(camera=CAMERA + "fov = nan\n"), ["camera.fov = nan", "finite"]),
    (scene_text(camera="[camera]\nposition = [0, inf, 3]\ntarget = [0, 0, 0]\n"),
     ["camera.position[1] = inf", "finite"]),
    (scene_text(tail="[[lights]]\ntype = 'point'\nposition = [0, 1, 0]\nintensity = -inf\n"),
     ["lights[0].intensity = -inf", "finite"]),
    (scene_text(tail="[techniques.pom]\nlayers = nan\n"), ["techniques.pom.layers = nan", "finite"]),
])
def test_non_finite_numbers(tmp_path, text, parts):
    error(tmp_path, text, *parts)


@pytest.mark.parametrize("text,parts", [
    (scene_text(camera="[camera]\nposition = [0, 0, 0]\ntarget = [0, 0, 0]\n"),
     ["camera.target = [0.0, 0.0, 0.0]", "equals camera.position"]),
    (scene_text(camera="[camera]\nposition = [0, 3, 0]\ntarget = [0, 0, 0]\n"), ["camera.up = [0, 1, 0]", "parallel"]),
    (scene_text(camera=CAMERA + "up = [0, 0, 0]\n"), ["camera.up = [0.0, 0.0, 0.0]", "nonzero"]),
    (scene_text(tail="[[lights]]\ntype = 'directional'\ndirection = [0, 0, 0]\n"), ["lights[0].direction", "nonzero"]),
    (scene_text(tail="[[lights]]\ntype = 'directional'\nposition = [0, 1, 0]\n"),
     ["lights[0].position = [0, 1, 0]", "not used by a directional light; expected direction"]),
    (scene_text(tail="[[lights]]\ntype = 'spot'\n"), ["lights[0].type = 'spot'", "directional, point"]),
    (scene_text(material=MATERIAL + "height = 'builtin:bumps'\nchannel = 'r'\n"),
     ["materials.rock.channel = 'r'", "height/depth file only"]),
    (scene_text(material=MATERIAL + "channel = 'x'\n"), ["materials.rock.channel = 'x'", "auto, r, g, b, a"]),
    (scene_text(material=MATERIAL + "normal = 'builtin:bumps'\n"),
     ["materials.rock.normal = 'builtin:bumps'", "normal map file"]),
])
def test_other_invalid_values(tmp_path, text, parts):
    error(tmp_path, text, *parts)


def test_long_values_are_shortened(tmp_path):
    msg = error(tmp_path, scene_text(f"[scene]\nname = {list(range(100))}"), "scene.name = [0, 1, 2", "...")
    assert len(msg) < len(str(tmp_path)) + 200


def test_parse_without_path_uses_placeholder():
    with pytest.raises(UserError, match=r"^<scene>: camera\.fov = 0: out of range"):
        parse_scene(scene_text(camera=CAMERA + "fov = 0\n"))


def test_load_scene_file_problems(tmp_path):
    with pytest.raises(UserError, match=r"nope\.toml: scene file not found"):
        load_scene(tmp_path / "nope.toml")
    (tmp_path / "latin1.toml").write_bytes("name = 'caf\xe9'".encode("latin-1"))
    with pytest.raises(UserError, match=r"latin1\.toml: not UTF-8"):
        load_scene(tmp_path / "latin1.toml")


def test_all_techniques_scene_lists_the_whole_registry():
    scene = load_scene(SCENES / "all_techniques.toml")
    assert scene.techniques == tuple(TECHNIQUES)


# --- geometry float32 renders correctly ---------------------------------------------------------------------------


@pytest.mark.parametrize("text,parts", [
    # a plane far larger than its distance to the camera: float32 vertices land nowhere near the screen
    (scene_text(objects=OBJECT.replace("[2.0, 2.0]", "[1e15, 1e15]")),
     ["objects[0].size = [1000000000000000.0, 1000000000000000.0]: out of range, expected |position| + |size| / 2 "
      "<= 6.554e+04", "65536 x the camera's distance to the object, here 1"]),
    # the same camera distance far from the origin: the object's position is what float32 cannot place
    (scene_text(camera="[camera]\nposition = [1e9, 1.0, 0.0]\ntarget = [1e9, 0.0, 0.5]\n",
                objects=OBJECT + "position = [1e9, 0.0, 0.0]\n"),
     ["objects[0].position = [1000000000.0, 0.0, 0.0]: out of range", "here 1;"]),
    # a box the camera sits in: its distance is to the nearest face, 1 unit in front
    (scene_text(objects="[[objects]]\ntype = 'box'\nmaterial = 'rock'\nsize = [1e7, 1e7, 8]\n"),
     ["objects[0].size = [10000000.0, 10000000.0, 8]: out of range", "here 1;"]),
    # a texture tiled so often that float32 texel coordinates skip texels
    (scene_text(material=MATERIAL.replace("[0.5, 0.4, 0.3]", "{ builtin = 'bricks', size = [512, 256] }")
                + "uv_scale = [1e5, 1e5]\n"),
     ["materials.rock.uv_scale = [100000.0, 100000.0]: out of range for its 512x256 texture",
      "expected uv_scale <= [32768, 65536]"]),
])
def test_geometry_float32_cannot_render_is_refused_with_the_range(tmp_path, text, parts):
    error(tmp_path, text, *parts)


def test_geometry_within_float32_range_loads(tmp_path):
    """Large but renderable: a 1000-unit plane seen from 1 unit, a far camera looking at a small plane, tiling at
    the limit, a tiny near plane (the box's distance, not the near plane, is the scale)."""
    load(tmp_path, scene_text(objects=OBJECT.replace("[2.0, 2.0]", "[1e3, 1e3]")))
    load(tmp_path, scene_text(camera="[camera]\nposition = [0.0, 1e9, 1e9]\ntarget = [0.0, 0.0, 0.0]\nfar = 1e10\n"
                                     "near = 0.1\n"))
    load(tmp_path, scene_text(material=MATERIAL.replace("[0.5, 0.4, 0.3]", "'builtin:bricks'")
                              + "uv_scale = [65536, 65536]\n"))
    load(tmp_path, scene_text(camera=CAMERA + "near = 1e-9\n"))


def test_a_material_folder_keeps_the_scenes_tiling_only_where_float32_can(tmp_path):
    from wgpuviewer.scene import with_folder_material

    folder = tmp_path / "rock"
    folder.mkdir()
    cv2.imwrite(str(folder / "rock_Color.png"), np.full((512, 512, 3), 128, np.uint8))
    scene = load(tmp_path, scene_text(material=MATERIAL + "uv_scale = [40000, 1]\n"))  # fine for a 1x1 colour
    with pytest.raises(UserError, match=r"--material .*rock: the scene's uv_scale = \[40000.0, 1.0\] is out of "
                                        r"range for its 512x512 texture"):
        with_folder_material(scene, folder)


# --- precomputed maps: [materials.X.maps] ------------------------------------------------------------------------

MAPS_MATERIAL = """
[materials.rock]
albedo = [0.5, 0.4, 0.3]
height = "h.npy"
[materials.rock.maps]
cone = "maps/h.cone.npy"
complexity = "maps/h.complexity.png"
"""


def batch_maps(tmp_path: Path) -> np.ndarray:
    """h.npy (8x8) and its cone and complexity maps in maps/, as maptools batch writes them; the height."""
    from maptools import cli as maptools_cli

    height = (np.indices((8, 8)).sum(axis=0) % 5 / 4).astype(np.float32)
    np.save(tmp_path / "h.npy", height)
    assert maptools_cli.main(["batch", str(tmp_path / "h.npy"), "-o", str(tmp_path / "maps"), "--kinds",
                              "cone,complexity", "--backend", "cpu"]) == 0
    return height


def test_a_material_names_maps_that_maptools_batch_built_from_its_height(tmp_path, capsys):
    batch_maps(tmp_path)
    material = load(tmp_path, scene_text(material=MAPS_MATERIAL)).materials["rock"]
    assert [(slot, ref.path) for slot, ref in material.maps] == [("cone", tmp_path / "maps" / "h.cone.npy"),
                                                                 ("complexity", tmp_path / "maps" / "h.complexity.png")]
    assert material.maps[0][1].origin == f"{tmp_path / 'x.toml'}: materials.rock.maps.cone = 'maps/h.cone.npy'"
    assert load(tmp_path, scene_text(material=MATERIAL)).materials["rock"].maps == ()


@pytest.mark.parametrize("case,replace,parts", [
    ("slot", ('cone = "maps/h.cone.npy"', 'maxmip = "maps/h.maxmip.npz"'),
     ["materials.rock.maps.maxmip = 'maps/h.maxmip.npz': unknown key; allowed: complexity, distance, "
      "distance_refined, cone"]),
    ("type", ('cone = "maps/h.cone.npy"', "cone = 3"),
     ["materials.rock.maps.cone = 3: expected the path of a cone map written by maptools batch"]),
    ("table", ('[materials.rock.maps]\ncone = "maps/h.cone.npy"\ncomplexity = "maps/h.complexity.png"',
               'maps = "maps"'), ["materials.rock.maps = 'maps': expected a table"]),
    ("builtin", ('height = "h.npy"', 'height = "builtin:bumps"'),
     ["materials.rock.maps.cone = 'maps/h.cone.npy': the material has no height file to check the map against"]),
    ("depth", ('height = "h.npy"', 'depth = "h.npy"'),
     ["materials.rock.maps.cone", "reads its file as depth; give the height file as height"]),
    ("missing", ('cone = "maps/h.cone.npy"', 'cone = "maps/gone.npy"'),
     ["materials.rock.maps.cone = 'maps/gone.npy': file not found (looked for"]),
    ("no record", ('cone = "maps/h.cone.npy"', 'cone = "copy.npy"'),
     ["materials.rock.maps.cone = 'copy.npy': copy.npy.json not found; name a map written by maptools batch"]),
    ("kind", ('cone = "maps/h.cone.npy"', 'cone = "maps/h.complexity.png"'),
     ["materials.rock.maps.cone = 'maps/h.complexity.png': is a complexity map (its record says so); expected a "
      "cone map"]),
    ("other height", None,
     ["materials.rock.maps.cone = 'maps/h.cone.npy': built from", "h.npy (sha256 ", "not from this material's "
      "height", "rebuild it: maptools batch", "--kinds cone"]),
    ("channel", ('height = "h.npy"', 'height = "h.npy"\nchannel = "r"'),
     ["materials.rock.maps.cone = 'maps/h.cone.npy': built from channel auto of the height file, and this material "
      "reads channel r; rebuild it with --channel r"]),
])
def test_a_named_map_not_built_from_the_materials_height_is_refused_naming_the_key(tmp_path, case, replace, parts):
    height = batch_maps(tmp_path)
    (tmp_path / "copy.npy").write_bytes((tmp_path / "maps" / "h.cone.npy").read_bytes())
    if case == "other height":
        np.save(tmp_path / "h.npy", height[::-1].copy())
    text = MAPS_MATERIAL if replace is None else MAPS_MATERIAL.replace(*replace)
    assert text != MAPS_MATERIAL or replace is None
    error(tmp_path, scene_text(material=text), *parts)


def test_material_shadows_depth_offset_address(tmp_path):
    rock = load(tmp_path, scene_text(material=MATERIAL + "shadows = 'soft'\ndepth_offset = true\naddress = 'clamp'\n")
                ).materials["rock"]
    assert (rock.shadows, rock.depth_offset, rock.address) == ("soft", True, "clamp")


# --- curved builtins, meshes and the showcase --------------------------------------------------


def test_curved_builtins_take_their_sizes(tmp_path):
    objects = "".join(f'[[objects]]\ntype = "{kind}"\nmaterial = "rock"\nsize = {size}\n'
                      for kind, size in (("sphere", "[0.5]"), ("cylinder", "[0.5, 2.0]"), ("torus", "[1.0, 0.25]")))
    scene = load(tmp_path, scene_text(objects=objects))
    assert [(o.type, o.size) for o in scene.objects] == [
        ("sphere", (0.5,)), ("cylinder", (0.5, 2.0)), ("torus", (1.0, 0.25))]


def test_showcase_scene():
    """Floor, walls, platforms, a glTF mesh, curved builtins, several lights and the relief settings in use."""
    scene = load_scene(SCENES / "showcase.toml")
    assert {"plane", "quad", "box", "mesh", "sphere", "torus"} <= {o.type for o in scene.objects}
    assert len(scene.lights) >= 2
    materials = scene.materials.values()
    assert {m.shadows for m in materials} >= {"hard", "soft"}
    assert any(m.depth_offset for m in materials) and any(m.address == "clamp" for m in materials)
    mesh = next(o for o in scene.objects if o.type == "mesh")
    assert mesh.file == SCENES / "showcase_assets" / "pillar.gltf" and mesh.scale == (0.9, 0.9, 0.9)
    assert np.allclose(mesh.size, (0.9 * 0.64, 0.9 * 4.0, 0.9 * 0.64), atol=1e-6)  # the origin-centred box


def test_showcase_pillar_is_what_its_script_writes():
    """The committed pillar.gltf is the output of scenes/showcase_assets.py (its source), byte for byte."""
    import importlib.util
    import json

    spec = importlib.util.spec_from_file_location("showcase_assets", SCENES / "showcase_assets.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    written = json.dumps(module.gltf(*module.pillar()), indent=1) + "\n"
    assert (SCENES / "showcase_assets" / "pillar.gltf").read_text() == written
