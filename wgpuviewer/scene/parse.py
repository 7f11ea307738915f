"""A scene file read into a ``Scene``: ``load_scene`` (the file: encoding, BOM), ``parse_scene`` (the TOML: every
section in turn; the camera, lights, objects and techniques here, the materials in ``materials``, the geometry
checked by ``limits``), ``default_scene_path``.
"""

from __future__ import annotations

import math
import tomllib
from importlib.resources import files
from pathlib import Path

from wgpuviewer.core.errors import FileError, UserError
from wgpuviewer.core.params import resolve_params
from wgpuviewer.meshes import DEFAULT_SIZES, MESH_SUFFIXES, NodeNotFound, load_mesh
from wgpuviewer.techniques import TECHNIQUES, get_technique
from wgpuviewer.textures import TextureRef

from .limits import MAX_DEPTH_RANGE, MAX_LIGHTS, check_geometry
from .materials import read_material
from .model import DEFAULT_LIGHT, MESH_DEFAULT_COLOR, OBJECT_SIZES, OBJECT_TYPES, Camera, Light, Material, Scene, SceneObject
from .table import MISSING, Table, is_number, reject_non_finite, show_value


def _camera(root: Table) -> Camera:
    t = Table(root.src, "camera", root.get("camera", MISSING, "a [camera] table"),
              ("position", "target", "up", "fov", "near", "far"))
    position, target = t.vector("position", 3), t.vector("target", 3)
    view = tuple(b - a for a, b in zip(position, target))
    if math.hypot(*view) < 1e-9:
        raise t.error("target", list(target), "equals camera.position; expected a point to look at")
    up = t.direction("up", [0.0, 1.0, 0.0])
    cross = (up[1] * view[2] - up[2] * view[1], up[2] * view[0] - up[0] * view[2], up[0] * view[1] - up[1] * view[0])
    if math.hypot(*cross) < 1e-6 * math.hypot(*view):
        raise t.error("up", t.data.get("up", [0, 1, 0]), "parallel to the view direction; expected another up vector")
    fov = t.number("fov", 60.0, 1, 179, exclusive=True)
    near = t.number("near", 0.05, lo=0, exclusive=True)
    far = t.number("far", 100.0, lo=0, exclusive=True)
    if far <= near:
        raise t.error("far", t.data.get("far", far), f"expected more than camera.near ({near:g})")
    if far > near * MAX_DEPTH_RANGE:
        raise t.error("near", t.data.get("near", near), f"too small for camera.far = {far:g}; expected camera.near "
                      f">= far / {MAX_DEPTH_RANGE:g} = {far / MAX_DEPTH_RANGE:g} (depth separates surfaces over "
                      f"that range)")
    return Camera(position, target, up, fov, near, far)


def _light(src: str, key: str, data) -> Light:
    t = Table(src, key, data, ("type", "direction", "position", "color", "intensity"))
    light_type = t.string("type", choices=("directional", "point"))
    placement, other = ("direction", "position") if light_type == "directional" else ("position", "direction")
    if other in t.data:
        raise t.error(other, t.data[other], f"not used by a {light_type} light; expected {placement}")
    color = t.vector("color", 3, [1.0, 1.0, 1.0], lo=0, hi=1)
    intensity = t.number("intensity", 1.0, lo=0)
    if light_type == "directional":
        return Light(light_type, color, intensity, direction=t.direction("direction"))
    return Light(light_type, color, intensity, position=t.vector("position", 3))


_OBJECT_KEYS = ("type", "material", "size", "position", "rotation", "file", "node", "scale")
_MESH_ONLY = ("file", "node", "scale")


def _object(src: str, key: str, data, materials: dict[str, Material], base: Path) -> SceneObject:
    """An [[objects]] table; a mesh without ``material`` adds the material its file gives to ``materials``."""
    t = Table(src, key, data, _OBJECT_KEYS)
    object_type = t.string("type", choices=OBJECT_TYPES)
    for name in _MESH_ONLY if object_type != "mesh" else ("size",):
        if name in t.data:
            raise t.error(name, t.data[name], f"not used by a {object_type} object; " + (
                "its size comes from its file: give scale = S or [sx, sy, sz]" if object_type == "mesh"
                else 'only type = "mesh" objects take file, node and scale'))
    material = t.string("material") if object_type != "mesh" or "material" in t.data else None
    if material is not None and material not in materials:
        raise t.error("material", material, f"unknown material; defined: {', '.join(materials) or 'none'}")
    position = t.vector("position", 3, [0.0, 0.0, 0.0])
    rotation = t.vector("rotation", 3, [0.0, 0.0, 0.0])
    if object_type != "mesh":
        size = t.vector("size", OBJECT_SIZES[object_type], list(DEFAULT_SIZES[object_type]), lo=0, exclusive=True)
        return SceneObject(type=object_type, material=material, size=size, position=position, rotation=rotation)
    value = t.string("file")
    path = t.file_path("file", value, base)
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise t.error("file", value, f"unsupported mesh file type; expected {', '.join(MESH_SUFFIXES)}")
    if not path.is_file():
        raise t.error("file", value, f"file not found (looked for {path})")
    node = t.string("node") if "node" in t.data else None
    scale = ((t.number("scale", 1.0, lo=0, exclusive=True),) * 3 if is_number(t.get("scale", 1.0, ""))
             else t.vector("scale", 3, [1.0, 1.0, 1.0], lo=0, exclusive=True))
    try:
        mesh = load_mesh(path, node, material=material is None)  # a scene material: the file's is not read
    except NodeNotFound as error:
        raise t.error("node", node, error.reason) from None
    except FileError as error:
        raise t.error("file", value, error.reason) from None
    if material is None:
        material = _file_material(t, value, path, node, mesh.material, materials)
    size = tuple(2 * h for h in mesh.half_extents(scale))
    return SceneObject(type=object_type, material=material, size=size, position=position, rotation=rotation, file=path,
                       node=node, scale=scale)


def _file_material(t: Table, value: str, path: Path, node: str | None, given, materials: dict) -> str:
    """The name of the material a mesh file gives (``meshes.FileMaterial``, or None: a plain grey), added to
    ``materials`` under ``FILE`` or ``FILE:NODE`` (a scene material of that name keeps it; the file's is then
    ``file FILE``)."""
    name = path.name + (f":{node}" if node is not None else "")
    if name in materials and not materials[name].name.startswith("file "):
        name = f"file {name}"
    origin = f"{t.src}: {t.path('file')} = {show_value(value)}"
    if given is not None and given.albedo is not None:
        albedo = given.albedo
    else:
        color = given.color if given is not None and given.color is not None else MESH_DEFAULT_COLOR
        albedo = TextureRef("color", color=color, origin=origin)
    materials.setdefault(name, Material(name=name, albedo=albedo, normal=given and given.normal,
                                        height=given and given.height))
    return name


def _techniques(root: Table, section: Table) -> tuple[str, tuple[str, ...], dict[str, dict]]:
    src = root.src
    listed = section.get("techniques", list(TECHNIQUES), "")
    if not (isinstance(listed, list) and listed and all(isinstance(x, str) for x in listed)):
        raise section.error("techniques", listed,
                            f"expected a non-empty array of technique names ({', '.join(TECHNIQUES)})")
    for i, name in enumerate(listed):
        get_technique(name, where=f"{src}: scene.techniques[{i}]")
        if name in listed[:i]:
            raise section.error("techniques", listed, f"{name!r} listed twice; expected each technique once")
    default = section.string("technique", listed[0])
    get_technique(default, where=f"{src}: scene.technique")
    if default not in listed:
        raise section.error("technique", default, f"not in scene.techniques ({', '.join(listed)}); add it there")
    overrides = root.table_of_tables("techniques")
    for name, params in overrides.items():
        get_technique(name, where=f"{src}: techniques.{name}")
        if name not in listed:
            raise root.error(f"techniques.{name}", params, f"technique not in scene.techniques ({', '.join(listed)})")
        # Checked here too so an unknown parameter's message shows its value.
        Table(src, f"techniques.{name}", params, tuple(p.name for p in TECHNIQUES[name].params))
    params = {
        name: resolve_params(TECHNIQUES[name], overrides.get(name), where=f"{src}: techniques.{name}.")
        for name in listed
    }
    return default, tuple(listed), params


def parse_scene(text: str, path: Path | str | None = None) -> Scene:
    """Scene from TOML text. ``path`` names the file in messages and anchors relative texture
    paths; None means paths relative to the working directory and messages prefixed "<scene>"."""
    src = str(path) if path is not None else "<scene>"
    base = Path(path).resolve().parent if path is not None else Path.cwd()
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise UserError(f"{src}: TOML syntax error: {e}") from None
    reject_non_finite(doc, src, "")
    root = Table(src, "", doc, ("scene", "camera", "lights", "materials", "objects", "techniques"))
    section = Table(src, "scene", doc.get("scene", {}), ("name", "technique", "techniques", "background"))
    technique, techniques, params = _techniques(root, section)

    raw_lights = root.array_of_tables("lights")
    if len(raw_lights) > MAX_LIGHTS:
        raise UserError(f"{src}: lights: {len(raw_lights)} [[lights]] tables; expected at most {MAX_LIGHTS} "
                        "(merge lights of the same direction, or drop the faintest)")
    lights = tuple(_light(src, f"lights[{i}]", x) for i, x in enumerate(raw_lights))
    materials = {
        name: read_material(src, name, data, base) for name, data in root.table_of_tables("materials").items()
    }
    root.get("objects", MISSING, "at least one [[objects]] table")
    raw_objects = root.array_of_tables("objects")
    if not raw_objects:
        raise root.error("objects", raw_objects, "expected at least one [[objects]] table")
    objects = tuple(_object(src, f"objects[{i}]", x, materials, base) for i, x in enumerate(raw_objects))
    camera = _camera(root)
    check_geometry(src, camera, objects, raw_objects)

    return Scene(
        path=Path(path).resolve() if path is not None else None,
        name=section.string("name", Path(path).stem if path is not None else "scene"),
        camera=camera,
        lights=lights or (DEFAULT_LIGHT,),  # absent or empty: one default light, never a black scene
        materials=materials,
        objects=objects,
        technique=technique,
        techniques=techniques,
        technique_params=params,
        background=section.vector("background", 3, [0.02, 0.02, 0.03], lo=0, hi=1),
    )


def load_scene(path) -> Scene:
    """Read and validate a scene file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise UserError(f"{path}: scene file not found") from None
    except IsADirectoryError:
        raise UserError(f"{path}: is a directory; expected a scene .toml file") from None
    except UnicodeDecodeError as e:
        raise UserError(f"{path}: not UTF-8 text ({e.reason} at byte {e.start}); save the scene as UTF-8") from None
    except OSError as e:
        raise UserError(f"{path}: cannot read scene file ({e.strerror})") from None
    if text.startswith("\ufeff"):
        raise UserError(f"{path}: starts with a UTF-8 byte-order mark (BOM), which TOML does not allow; "
                        "save the file as UTF-8 without BOM (most editors: encoding 'UTF-8', not 'UTF-8 with BOM')")
    return parse_scene(text, path)


def default_scene_path() -> Path:
    """The default scene shipped inside the package (scenes/ is the package wgpuviewer.scenes)."""
    return Path(str(files("wgpuviewer.scenes") / "default.toml"))
