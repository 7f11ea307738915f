"""Scenes: TOML files validated into frozen dataclasses.

Conventions: right-handed world, +Y up; angles in degrees; colours are linear RGB in [0, 1].
Textures are only referenced here (textures.TextureRef); textures.py loads them lazily.
Geometry is held to what the GPU's float32 renders correctly (``MAX_VIEW_RATIO``, ``MAX_TEXEL_COORDINATE``).
Every problem is a one-line UserError naming the file, the key path, the value and what is
expected. ``scenes/default.toml`` documents the format.
"""

from __future__ import annotations

import logging
import math
import tomllib
from dataclasses import dataclass, replace
from importlib.resources import files
from pathlib import Path

import numpy as np

from wgpuviewer.core.errors import FileError, UserError
from wgpuviewer.core.images import read_header
from wgpuviewer.core.sidecar import file_sha256, is_recorded, read_record
from wgpuviewer.techniques import TECHNIQUES, get_technique, resolve_params

from . import camera as cam
from .meshes import BUILTIN_SHAPES, MESH_SUFFIXES, NodeNotFound, load_mesh
from .textures import (
    BUILTINS,
    FOLDER_EXTS,
    FOLDER_SLOTS,
    MAX_BUILTIN_SIZE,
    FolderFiles,
    TextureRef,
    file_role,
    find_material_files,
)

log = logging.getLogger("wgpuviewer.scene")

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Camera:
    """Perspective camera; ``fov`` is the vertical field of view in degrees, ``up`` is unit length."""

    position: Vec3
    target: Vec3
    up: Vec3 = (0.0, 1.0, 0.0)
    fov: float = 60.0
    near: float = 0.05
    far: float = 100.0


@dataclass(frozen=True)
class Light:
    """A directional light (``direction``: unit vector the light travels along) or a point light."""

    kind: str
    color: Vec3 = (1.0, 1.0, 1.0)
    intensity: float = 1.0
    direction: Vec3 | None = None
    position: Vec3 | None = None


@dataclass(frozen=True)
class Material:
    """Surface textures and relief settings.

    ``normal`` None means: derive normals from the height map if there is one, else flat.
    ``height_is_depth`` records that the scene gave ``depth`` (0 = top) rather than ``height``
    (1 = top); textures.load_height / load_depth take it as ``is_depth``. ``height_scale`` is the
    relief depth in UV units; ``uv_scale`` tiles the textures and ``uv_offset`` then shifts them, in tiles
    (glTF's KHR_texture_transform order: ``uv * uv_scale + uv_offset``). ``maps``: (slot, file) of the
    precomputed maps the scene names (``[materials.X.maps]``), each checked against the height file it was built
    from; the renderer serves them instead of building those slots (``maptools.cache.serving``). ``shadows``: the
    relief's self-shadowing (``SHADOW_MODES``); ``depth_offset`` writes the traced hit's depth so other geometry
    intersects the relief; ``address``: ``repeat`` tiles the textures, ``clamp`` makes the uv square the relief's
    extent (rays leaving it before a hit are discarded: silhouettes).
    """

    name: str
    albedo: TextureRef
    normal: TextureRef | None = None
    normal_y: str = "opengl"
    height: TextureRef | None = None
    height_is_depth: bool = False
    height_scale: float = 0.05
    uv_scale: tuple[float, float] = (1.0, 1.0)
    uv_offset: tuple[float, float] = (0.0, 0.0)
    maps: tuple[tuple[str, TextureRef], ...] = ()
    shadows: str = "off"
    depth_offset: bool = False
    address: str = "repeat"


#: Self-shadowing modes of a material (``shadows = ...``; the render flag ``--shadows`` overrides every material).
SHADOW_MODES = ("off", "hard", "soft")
#: Texture addressing of a material: ``repeat`` tiles, ``clamp`` ends the relief at the uv domain's edge.
ADDRESS_MODES = ("repeat", "clamp")


@dataclass(frozen=True)
class SceneObject:
    """A shape with a material. Plane: in XZ facing +Y, size (width along X, depth along Z);
    quad: in XY facing +Z, size (width along X, height along Y); box: size (x, y, z); sphere: size (radius,);
    cylinder: along Y, size (radius, height); torus: around Y, size (major radius, minor radius) (``meshes``).
    mesh: the triangles of ``file`` (glTF or OBJ; ``node``: one node or object of it), scaled by ``scale``; its
    ``size`` is that of the origin-centred box holding the scaled mesh.
    ``rotation`` is Euler XYZ in degrees, applied before ``position``.
    """

    kind: str
    material: str
    size: tuple[float, ...]
    position: Vec3 = (0.0, 0.0, 0.0)
    rotation: Vec3 = (0.0, 0.0, 0.0)
    file: Path | None = None
    node: str | None = None
    scale: Vec3 = (1.0, 1.0, 1.0)


@dataclass(frozen=True)
class Scene:
    """A validated scene. ``technique_params`` holds the full resolved parameters of every
    technique in ``techniques`` (registry defaults merged with the scene's ``[techniques.NAME]``).
    """

    path: Path | None
    name: str
    camera: Camera
    lights: tuple[Light, ...]
    materials: dict[str, Material]
    objects: tuple[SceneObject, ...]
    technique: str
    techniques: tuple[str, ...]
    technique_params: dict[str, dict]
    background: Vec3 = (0.02, 0.02, 0.03)


#: Builtin object type -> how many numbers its ``size`` has (``meshes.BUILTIN_SHAPES`` names them).
OBJECT_SIZES = {kind: len(keys) for kind, (keys, _) in BUILTIN_SHAPES.items()}
#: Every object type: the builtins and ``mesh`` (a glTF or OBJ file).
OBJECT_TYPES = (*OBJECT_SIZES, "mesh")
#: Albedo of a mesh whose file gives it no material.
MESH_DEFAULT_COLOR = (0.8, 0.8, 0.8)
#: Most [[lights]] a scene may have: the renderer's Frame uniform holds them all (32 bytes each), and the
#: shader loops over the scene's count only.
MAX_LIGHTS = 256
#: camera.far / camera.near at most: reversed-Z float depth separates surfaces over this range.
MAX_DEPTH_RANGE = 1e12
#: Float32 vertices. The GPU transforms vertices in float32 (24-bit significand): a vertex, or the camera, at
#: distance P from the world origin lands within about P * 2^-24 of where it belongs, an angle of (P / d) * 2^-24
#: seen from a distance d. Held to 2^-8 radian (a quarter of a degree, under 3 pixels of the default 1280x720
#: frame at the default 60-degree field of view): P / d <= 2^16 for every object's reach |position| + |size| / 2,
#: d being the camera's distance to the object (at least camera.near). The camera, within d of the object, is
#: then within (2^16 + 1) d of the origin. Measured on the software adapter at 64x48 pixels: a plane 1 unit below
#: the camera loses pixels from P / d = 7e5 on and vanishes beyond 2e7. (The perspective study's largest
#: coordinate offset, 1e7 texels, reaches P / d = 2.2e4.)
MAX_VIEW_RATIO = 2.0 ** 16
#: Largest texel coordinate, uv_scale x the texture's side: beyond 2^24 float32's spacing exceeds one texel, so
#: hit points skip texels and the texture tears.
MAX_TEXEL_COORDINATE = 2 ** 24
CHANNELS = ("auto", "r", "g", "b", "a")
_MISSING = object()


def _show(value) -> str:
    """repr of a value for messages: one line, bounded length."""
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _range_text(lo: float | None, hi: float | None, exclusive: bool) -> str:
    if lo is not None and hi is not None:
        return f"expected {lo:g} to {hi:g}" + (" (exclusive)" if exclusive else "")
    if lo is not None:
        return f"expected {'>' if exclusive else '>='} {lo:g}"
    return f"expected {'<' if exclusive else '<='} {hi:g}"


def _in_range(x: float, lo: float | None, hi: float | None, exclusive: bool) -> bool:
    if exclusive:
        return (lo is None or x > lo) and (hi is None or x < hi)
    return (lo is None or x >= lo) and (hi is None or x <= hi)


def _is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _normalise(v: tuple[float, ...]) -> Vec3:
    length = math.hypot(*v)
    return tuple(c / length for c in v)


#: Used when a scene gives no lights: from above, slightly from the front left.
DEFAULT_LIGHT = Light("directional", direction=_normalise((0.4, -1.0, -0.3)))


class _Table:
    """One TOML table being read: typed getters whose errors carry the file and key path."""

    def __init__(self, src: str, key: str, data, allowed: tuple[str, ...]):
        if not isinstance(data, dict):
            raise UserError(f"{src}: {key} = {_show(data)}: expected a table")
        self.src, self.key, self.data = src, key, data
        for name, value in data.items():
            if name not in allowed:
                raise self.error(name, value, f"unknown key; allowed: {', '.join(allowed) or 'none'}")

    def path(self, name: str) -> str:
        return f"{self.key}.{name}" if self.key else name

    def error(self, name: str, value, expected: str) -> UserError:
        return UserError(f"{self.src}: {self.path(name)} = {_show(value)}: {expected}")

    def get(self, name: str, default, expected: str):
        """The raw value, ``default`` if absent; a missing key without default is an error."""
        if name in self.data:
            return self.data[name]
        if default is _MISSING:
            raise UserError(f"{self.src}: {self.path(name)}: missing required key; expected {expected}")
        return default

    def number(self, name, default=_MISSING, lo=None, hi=None, exclusive=False) -> float:
        value = self.get(name, default, "a number")
        if not _is_number(value):
            raise self.error(name, value, "expected a number")
        if not _in_range(value, lo, hi, exclusive):
            raise self.error(name, value, f"out of range, {_range_text(lo, hi, exclusive)}")
        return float(value)

    def vector(self, name, n, default=_MISSING, lo=None, hi=None, exclusive=False) -> tuple[float, ...]:
        value = self.get(name, default, f"an array of {n} numbers")
        if not (isinstance(value, (list, tuple)) and len(value) == n and all(map(_is_number, value))):
            raise self.error(name, value, f"expected an array of {n} numbers")
        if not all(_in_range(x, lo, hi, exclusive) for x in value):
            raise self.error(name, value, f"out of range, {n} numbers each {_range_text(lo, hi, exclusive)}")
        return tuple(float(x) for x in value)

    def direction(self, name, default=_MISSING) -> Vec3:
        value = self.vector(name, 3, default)
        if math.hypot(*value) < 1e-9:
            raise self.error(name, list(value), "zero vector; expected a nonzero direction")
        return _normalise(value)

    def string(self, name, default=_MISSING, choices: tuple[str, ...] = ()) -> str:
        value = self.get(name, default, f"one of {', '.join(choices)}" if choices else "a string")
        if not isinstance(value, str):
            raise self.error(name, value, "expected a string")
        if choices and value not in choices:
            raise self.error(name, value, f"expected one of {', '.join(choices)}")
        return value

    def boolean(self, name, default=_MISSING) -> bool:
        value = self.get(name, default, "true or false")
        if not isinstance(value, bool):
            raise self.error(name, value, "expected true or false")
        return value

    def array_of_tables(self, name: str) -> list:
        """``[[name]]`` entries; [] when absent."""
        value = self.data.get(name, [])
        if not (isinstance(value, list) and all(isinstance(x, dict) for x in value)):
            raise self.error(name, value, f"expected an array of tables ([[{name}]])")
        return value

    def table_of_tables(self, name: str) -> dict:
        """``[name.KEY]`` sections as {KEY: raw table}; {} when absent."""
        value = self.data.get(name, {})
        if not isinstance(value, dict):
            raise self.error(name, value, f"expected tables ([{name}.NAME])")
        return value


def _reject_non_finite(value, src: str, key: str) -> None:
    """TOML allows nan and inf; no scene value may be either."""
    if isinstance(value, float) and not math.isfinite(value):
        raise UserError(f"{src}: {key} = {value!r}: expected a finite number")
    if isinstance(value, dict):
        for name, item in value.items():
            _reject_non_finite(item, src, f"{key}.{name}" if key else name)
    elif isinstance(value, list):
        for i, item in enumerate(value):
            _reject_non_finite(item, src, f"{key}[{i}]")


_TEXTURE_FORMS = "'builtin:NAME', { builtin = NAME, size = [W, H] } or a file path"


def _texture(t: _Table, name: str, base: Path, color_ok: bool = False, required: bool = False) -> TextureRef | None:
    """A texture value (builtin, file or, where ``color_ok``, an RGB array); None when absent. A file's header is
    read here (format, size, limits: cheap), so a bad file is reported at once against its key."""
    expected = _TEXTURE_FORMS + (" or an RGB array [r, g, b]" if color_ok else "")
    value = t.get(name, _MISSING if required else None, f"a texture: {expected}")
    if value is None:
        return None
    origin = f"{t.src}: {t.path(name)} = {_show(value)}"
    if isinstance(value, list) and color_ok:
        return TextureRef("color", color=t.vector(name, 3, lo=0, hi=1), origin=origin)
    if isinstance(value, dict):
        spec = _Table(t.src, t.path(name), value, ("builtin", "size"))
        builtin = spec.string("builtin")
        size = spec.get("size", [256, 256], "")
        if not (isinstance(size, list) and len(size) == 2
                and all(isinstance(s, int) and not isinstance(s, bool) and 1 <= s <= MAX_BUILTIN_SIZE
                        for s in size)):
            raise spec.error("size", size, f"expected [width, height], integers 1 to {MAX_BUILTIN_SIZE}")
        return _builtin_ref(spec, "builtin", builtin, tuple(size), origin)
    if not isinstance(value, str):
        raise t.error(name, value, f"expected a texture: {expected}")
    if value.startswith("builtin:"):
        return _builtin_ref(t, name, value, (256, 256), origin)
    return _file_ref(t, name, value, (base / Path(value).expanduser()).resolve())  # base is ignored for absolute


def _file_ref(t: _Table, name: str, value, path: Path) -> TextureRef:
    """A file texture at ``path`` named by key ``name`` (value ``value``), its header checked."""
    if not path.exists():
        raise t.error(name, value, f"file not found (looked for {path})")
    try:
        read_header(path)
    except FileError as error:
        raise t.error(name, value, error.reason) from None
    return TextureRef("file", path=path, origin=f"{t.src}: {t.path(name)} = {_show(value)}")


def _builtin_ref(t: _Table, key: str, value: str, size: tuple[int, int], origin: str) -> TextureRef:
    name = value.removeprefix("builtin:")
    if name not in BUILTINS:
        raise t.error(key, value, f"unknown builtin texture; expected one of {', '.join(BUILTINS)}")
    return TextureRef("builtin", name=name, size=size, origin=origin)


def _camera(root: _Table) -> Camera:
    t = _Table(root.src, "camera", root.get("camera", _MISSING, "a [camera] table"),
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
    t = _Table(src, key, data, ("type", "direction", "position", "color", "intensity"))
    kind = t.string("type", choices=("directional", "point"))
    placement, other = ("direction", "position") if kind == "directional" else ("position", "direction")
    if other in t.data:
        raise t.error(other, t.data[other], f"not used by a {kind} light; expected {placement}")
    color = t.vector("color", 3, [1.0, 1.0, 1.0], lo=0, hi=1)
    intensity = t.number("intensity", 1.0, lo=0)
    if kind == "directional":
        return Light(kind, color, intensity, direction=t.direction("direction"))
    return Light(kind, color, intensity, position=t.vector("position", 3))


def _material(src: str, name: str, data, base: Path) -> Material:
    t = _Table(src, f"materials.{name}", data,
               ("folder", "albedo", "normal", "normal_y", "height", "depth", "height_scale", "uv_scale", "uv_offset",
                "channel", "maps", "shadows", "depth_offset", "address"))
    folder = _folder(t, base)
    albedo = _texture(t, "albedo", base, color_ok=True, required=folder is None) or (folder and folder["albedo"])
    if albedo is None:
        raise t.error("folder", t.data["folder"], "has no albedo (NAME_Color, name_diff_1k, albedo, basecolor or "
                                                  "diffuse); add one, or give albedo = ...")
    normal = _texture(t, "normal", base)
    if normal is not None and normal.kind != "file":
        raise t.error("normal", t.data["normal"],
                      "expected a normal map file (omit it to derive normals from the height map)")
    if "height" in t.data and "depth" in t.data:
        raise t.error("depth", t.data["depth"], "both height and depth given; expected only one of them")
    is_depth = "depth" in t.data
    height = _texture(t, "depth" if is_depth else "height", base)
    if folder is not None:  # keys given in the table win over the folder's files
        normal = normal if "normal" in t.data else folder["normal"]
        height = height if "height" in t.data or is_depth else folder["height"]
    channel = t.string("channel", "auto", CHANNELS)
    if channel != "auto":
        if height is None or height.kind != "file":
            raise t.error("channel", channel, "applies to a height/depth file only; expected no channel here")
        height = replace(height, channel=channel)
    default_y = folder["normal_y"] if folder is not None and "normal" not in t.data else "opengl"
    uv_scale = t.vector("uv_scale", 2, [1.0, 1.0], lo=0, exclusive=True)
    problem = _texel_coordinate_problem(uv_scale, (albedo, normal, height))
    if problem:
        raise t.error("uv_scale", t.data.get("uv_scale", list(uv_scale)), problem)
    material = Material(
        name=name,
        albedo=albedo,
        normal=normal,
        normal_y=t.string("normal_y", default_y, ("opengl", "directx")),
        height=height,
        height_is_depth=is_depth,
        height_scale=t.number("height_scale", 0.05, 0, 1),
        uv_scale=uv_scale,
        uv_offset=t.vector("uv_offset", 2, [0.0, 0.0]),  # any finite value: the renderer drops its whole tiles
        maps=_named_maps(t, base, height, is_depth),
        shadows=t.string("shadows", "off", SHADOW_MODES),
        depth_offset=t.boolean("depth_offset", False),
        address=t.string("address", "repeat", ADDRESS_MODES),
    )
    if folder is not None:
        report_folder(folder)
    return material


#: The slots a scene may name a precomputed map for (``[materials.X.maps]``, files ``maptools batch`` writes): those
#: the renderer builds from the height map itself (maxmip and quadmax come from the bilinear cells' maxima; a normal
#: map is named by ``normal = ...``).
NAMED_MAPS = ("complexity", "distance", "distance_refined", "cone")


def _named_maps(t: _Table, base: Path, height: TextureRef | None, is_depth: bool) -> tuple[tuple[str, TextureRef], ...]:
    """``[materials.X.maps]`` SLOT = "FILE" (relative to the scene): each file's batch record (core.sidecar) must say
    it is a map of that slot built from the material's height file (the same bytes, read through the same channel).
    The renderer checks the rest (options, maptools version, the file's own bytes) when it serves the map."""
    raw = t.get("maps", None, "")
    if raw is None:
        return ()
    maps = _Table(t.src, t.path("maps"), raw, NAMED_MAPS)
    named = []
    height_sha256 = ""
    for slot, value in maps.data.items():
        if not isinstance(value, str):
            raise maps.error(slot, value, f"expected the path of a {slot} map written by maptools batch")
        if height is None or height.kind != "file":
            raise maps.error(slot, value, "the material has no height file to check the map against; give "
                                          "height = \"...\", the file the map was built from")
        if is_depth:
            raise maps.error(slot, value, "maptools batch builds maps from height files (1 = top), and this material "
                                          "reads its file as depth; give the height file as height = \"...\"")
        path = (base / Path(value).expanduser()).resolve()
        if not path.is_file():
            raise maps.error(slot, value, f"file not found (looked for {path})")
        try:
            record = read_record(path)
        except FileError as error:
            raise maps.error(slot, value, f"{Path(error.path).name} {error.reason}") from None
        if record.kind != slot:
            raise maps.error(slot, value, f"is a {record.kind} map (its record says so); expected a {slot} map")
        height_sha256 = height_sha256 or file_sha256(height.path)
        if record.input_sha256 != height_sha256:
            raise maps.error(slot, value, f"built from {record.input} (sha256 {record.input_sha256[:12]}...), not "
                                          f"from this material's height {height.path} (sha256 {height_sha256[:12]}...); "
                                          f"rebuild it: maptools batch {height.path} -o {path.parent} --kinds {slot}")
        if record.channel != height.channel:
            raise maps.error(slot, value, f"built from channel {record.channel} of the height file, and this material "
                                          f"reads channel {height.channel}; rebuild it with --channel {height.channel}")
        named.append((slot, TextureRef("file", path=path, origin=f"{t.src}: {maps.path(slot)} = {_show(value)}")))
    return tuple(named)


def _texture_size(ref: TextureRef | None) -> tuple[int, int]:
    """(width, height) of a texture without loading it: a builtin's size, a file's header; 1x1 for a colour."""
    if ref is None or ref.kind == "color":
        return 1, 1
    if ref.kind == "file":
        header = read_header(ref.path)  # checked when the reference was made: cheap, and it does not fail here
        return header.width, header.height
    return ref.size


def _texel_coordinate_problem(uv_scale: tuple[float, float], refs) -> str:
    """Why ``uv_scale`` tiles the textures ``refs`` beyond MAX_TEXEL_COORDINATE ('' when it does not)."""
    sizes = [_texture_size(ref) for ref in refs]
    width, height = max(w for w, _ in sizes), max(h for _, h in sizes)
    reach = max(uv_scale[0] * width, uv_scale[1] * height)
    if reach <= MAX_TEXEL_COORDINATE:
        return ""
    most = [MAX_TEXEL_COORDINATE / width, MAX_TEXEL_COORDINATE / height]
    return (f"out of range for its {width}x{height} texture: texel coordinates reach {reach:.3g}, beyond the "
            f"{MAX_TEXEL_COORDINATE} up to which float32 addresses every texel; expected uv_scale <= "
            f"[{most[0]:g}, {most[1]:g}]")


def uv_scale_problem(material: Material, uv_scale: tuple[float, float]) -> str:
    """Why tiling ``material``'s textures by ``uv_scale`` goes beyond MAX_TEXEL_COORDINATE ('' when it does not):
    the check a scene's ``uv_scale`` passes, for a tiling given elsewhere (``render --uv-scale``, the Python API)."""
    return _texel_coordinate_problem(uv_scale, (material.albedo, material.normal, material.height))


def _folder(t: _Table, base: Path) -> dict | None:
    """``folder = "DIR"``: the material's files found by name (textures.find_material_files); None if absent."""
    value = t.get("folder", None, "a folder path")
    if value is None:
        return None
    if not isinstance(value, str):
        raise t.error("folder", value, "expected a folder path (a string)")
    path = (base / Path(value).expanduser()).resolve()
    if not path.exists():
        raise t.error("folder", value, f"folder not found (looked for {path})")
    # keys given next to the folder win: the folder is not searched for their slots (depth fills the height's)
    named = [slot for slot in FOLDER_SLOTS if slot in t.data or (slot == "height" and "depth" in t.data)]
    try:
        return folder_refs(path, f"{t.src}: {t.path('folder')} = {_show(value)}", named)
    except FileError as error:
        raise t.error("folder", value, error.reason) from None


def folder_refs(path: Path, where: str, named=()) -> dict:
    """albedo/normal/height TextureRefs (None where absent or ``named``: given by the scene) and normal_y of the
    material folder ``path``; each file's header checked; problems are reported against ``where`` (and the file's
    name)."""
    found = find_material_files(path, named)
    refs: dict = {"normal_y": found.normal_y, "report": f"{where}: {folder_summary(path, found, named)}"}
    for slot in ("albedo", "normal", "height"):
        file = getattr(found, slot)
        refs[slot] = None
        if file is not None:
            try:
                read_header(file)
            except FileError as error:
                raise FileError(path, f"{file.name}: {error.reason}") from None
            refs[slot] = TextureRef("file", path=file, origin=f"{where} ({file.name})")
    return refs


def folder_summary(path: Path, found: FolderFiles, named=()) -> str:
    """What the material folder ``path`` gave each slot (``found``; ``named``: the slots the scene gives itself)
    and every other entry with why it was left out, grouped by reason."""
    picked = []
    for slot in FOLDER_SLOTS:
        file = getattr(found, slot)
        convention = f" ({_CONVENTIONS[found.normal_y]})" if slot == "normal" else ""
        picked.append(f"{slot} {file.name}{convention}" if file is not None
                      else f"{slot} from the scene" if slot in named else f"{slot} none")
    chosen = {getattr(found, slot) for slot in FOLDER_SLOTS}
    ignored: dict[str, list[str]] = {}
    for entry in sorted(path.iterdir()):
        if entry not in chosen:
            ignored.setdefault(_left_out_because(entry, found, named), []).append(entry.name)
    left_out = "; ".join(f"{', '.join(names)} ({why})" for why, names in ignored.items())
    return f"picked {', '.join(picked)}; " + (f"ignored {left_out}" if left_out else "nothing else in the folder")


def _left_out_because(entry: Path, found: FolderFiles, named) -> str:
    """Why the material-folder scan (``textures.find_material_files``) passed over ``entry``."""
    if entry.is_dir():
        return "a folder"
    if entry.suffix.lower() not in FOLDER_EXTS:
        return "not an image file"
    if is_recorded(entry):
        return "written by maptools batch"
    role = file_role(entry)
    if role is None:
        return "no albedo, normal or height in its name"
    if role[0] in named:
        return f"the scene gives the {role[0]}"
    if role[0] == "normal" and role[1] != found.normal_y:
        return f"{_CONVENTIONS[role[1]]} normal map; the {_CONVENTIONS[found.normal_y]} one is used"
    return "not used"


_CONVENTIONS = {"opengl": "OpenGL", "directx": "DirectX"}


#: The folder lines already printed (``report_folder``): once per folder and what it gave.
_REPORTED: set[str] = set()


def report_folder(refs: dict) -> None:
    """Say once what a material folder gave (``folder_refs``' report), as a ``wgpuviewer.scene`` note (INFO): the
    CLIs print those, so the user sees which files ``--material`` or ``folder =`` took and which it left out."""
    if refs["report"] not in _REPORTED:
        _REPORTED.add(refs["report"])
        log.info(refs["report"])


def with_folder_material(scene: Scene, folder: Path) -> Scene:
    """``scene`` with the material folder ``folder`` on its first plane (``--material DIR``): its albedo, normal
    and height files found by name, the plane's relief depth and tiling kept."""
    where = f"--material {folder}"
    plane = next((i for i, o in enumerate(scene.objects) if o.kind == "plane"), None)
    if plane is None:
        raise UserError(f"{where}: the scene {scene.path or scene.name} has no plane to show the material on; "
                        "use a scene with a [[objects]] type = \"plane\"")
    if not folder.exists():
        raise UserError(f"{where}: folder not found (looked for {folder.resolve()})")
    try:
        refs = folder_refs(folder.resolve(), where)
    except FileError as error:
        raise UserError(f"{where}: {error.reason}") from None
    if refs["albedo"] is None:
        raise UserError(f"{where}: no albedo file (NAME_Color, name_diff_1k, albedo, basecolor or diffuse)")
    old = scene.materials[scene.objects[plane].material]
    problem = _texel_coordinate_problem(old.uv_scale, (refs["albedo"], refs["normal"], refs["height"]))
    if problem:
        raise UserError(f"{where}: the scene's uv_scale = {list(old.uv_scale)} is {problem}")
    name = f"folder {folder.name}"
    material = Material(name=name, albedo=refs["albedo"], normal=refs["normal"], normal_y=refs["normal_y"],
                        height=refs["height"], height_scale=old.height_scale, uv_scale=old.uv_scale,
                        uv_offset=old.uv_offset)
    objects = list(scene.objects)
    objects[plane] = replace(objects[plane], material=name)
    report_folder(refs)
    return replace(scene, materials={**scene.materials, name: material}, objects=tuple(objects),
                   name=f"{scene.name} with {folder.name}")


_OBJECT_KEYS = ("type", "material", "size", "position", "rotation", "file", "node", "scale")
_MESH_ONLY = ("file", "node", "scale")


def _object(src: str, key: str, data, materials: dict[str, Material], base: Path) -> SceneObject:
    """An [[objects]] table; a mesh without ``material`` adds the material its file gives to ``materials``."""
    t = _Table(src, key, data, _OBJECT_KEYS)
    kind = t.string("type", choices=OBJECT_TYPES)
    for name in _MESH_ONLY if kind != "mesh" else ("size",):
        if name in t.data:
            raise t.error(name, t.data[name], f"not used by a {kind} object; " + (
                "its size comes from its file: give scale = S or [sx, sy, sz]" if kind == "mesh"
                else 'only type = "mesh" objects take file, node and scale'))
    material = t.string("material") if kind != "mesh" or "material" in t.data else None
    if material is not None and material not in materials:
        raise t.error("material", material, f"unknown material; defined: {', '.join(materials) or 'none'}")
    position = t.vector("position", 3, [0.0, 0.0, 0.0])
    rotation = t.vector("rotation", 3, [0.0, 0.0, 0.0])
    if kind != "mesh":
        size = t.vector("size", OBJECT_SIZES[kind], lo=0, exclusive=True)
        return SceneObject(kind=kind, material=material, size=size, position=position, rotation=rotation)
    value = t.string("file")
    path = (base / Path(value).expanduser()).resolve()
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise t.error("file", value, f"unsupported mesh file type; expected {', '.join(MESH_SUFFIXES)}")
    if not path.is_file():
        raise t.error("file", value, f"file not found (looked for {path})")
    node = t.string("node") if "node" in t.data else None
    scale = ((t.number("scale", 1.0, lo=0, exclusive=True),) * 3 if _is_number(t.get("scale", 1.0, ""))
             else t.vector("scale", 3, [1.0, 1.0, 1.0], lo=0, exclusive=True))
    try:
        mesh = load_mesh(path, node)
    except NodeNotFound as error:
        raise t.error("node", node, error.reason) from None
    except FileError as error:
        raise t.error("file", value, error.reason) from None
    if material is None:
        material = _file_material(t, value, path, node, mesh.material, materials)
    size = tuple(2 * h for h in mesh.half_extents(scale))
    return SceneObject(kind=kind, material=material, size=size, position=position, rotation=rotation, file=path,
                       node=node, scale=scale)


def _file_material(t: _Table, value: str, path: Path, node: str | None, given, materials: dict) -> str:
    """The name of the material a mesh file gives (``meshes.FileMaterial``, or None: a plain grey), added to
    ``materials`` under ``FILE`` or ``FILE:NODE`` (a scene material of that name keeps it; the file's is then
    ``file FILE``)."""
    name = path.name + (f":{node}" if node is not None else "")
    if name in materials and not materials[name].name.startswith("file "):
        name = f"file {name}"
    origin = f"{t.src}: {t.path('file')} = {_show(value)}"
    if given is not None and given.albedo is not None:
        albedo = given.albedo
    else:
        color = given.color if given is not None and given.color is not None else MESH_DEFAULT_COLOR
        albedo = TextureRef("color", color=color, origin=origin)
    materials.setdefault(name, Material(name=name, albedo=albedo, normal=given and given.normal,
                                        height=given and given.height))
    return name


_HALF_EXTENTS = {  # object kind -> its half extents (local x, y, z) from its size: the box holding it
    "plane": lambda s: (s[0] / 2, 0.0, s[1] / 2),
    "quad": lambda s: (s[0] / 2, s[1] / 2, 0.0),
    "box": lambda s: (s[0] / 2, s[1] / 2, s[2] / 2),
    "sphere": lambda s: (s[0], s[0], s[0]),
    "cylinder": lambda s: (s[0], s[1] / 2, s[0]),
    "torus": lambda s: (s[0] + s[1], s[1], s[0] + s[1]),
    "mesh": lambda s: (s[0] / 2, s[1] / 2, s[2] / 2),
}


def _distance_to(obj: SceneObject, point) -> float:
    """Float64 distance from ``point`` to the surface of ``obj`` (a plane's or quad's rectangle, a box's faces; the
    box holding a curved shape or a mesh: a lower bound of the distance outside it, the distance to its faces
    inside)."""
    rotation = cam.rotation_xyz(obj.rotation)[:3, :3]
    local = np.abs(rotation.T @ (np.asarray(point, np.float64) - obj.position))
    half = np.asarray(_HALF_EXTENTS[obj.kind](obj.size))
    outside = float(np.linalg.norm(np.maximum(local - half, 0.0)))
    return outside if outside > 0 else float(np.min(half - local))  # inside a box: to its nearest face


def _check_geometry(src: str, camera: Camera, objects: tuple[SceneObject, ...], raw_objects: list[dict]) -> None:
    """Every object within float32's range for the camera's view of it (MAX_VIEW_RATIO). The camera's own
    |position| is then within (MAX_VIEW_RATIO + 1) times its distance to the nearest object: no check of its own."""
    ratio = MAX_VIEW_RATIO
    for i, (obj, raw) in enumerate(zip(objects, raw_objects, strict=True)):
        d = max(_distance_to(obj, camera.position), camera.near)
        offset = math.hypot(*obj.position)
        reach = offset + math.hypot(*_HALF_EXTENTS[obj.kind](obj.size))
        if reach > ratio * d:
            key = "position" if offset > ratio * d else "size"
            raise UserError(f"{src}: objects[{i}].{key} = {_show(raw.get(key, [0, 0, 0]))}: out of range, expected "
                            f"|position| + |size| / 2 <= {ratio * d:.4g} (float32 places vertices within 1/4 degree "
                            f"up to {ratio:.0f} x the camera's distance to the object, here {d:.4g}; it reaches "
                            f"{reach:.4g})")


def _techniques(root: _Table, section: _Table) -> tuple[str, tuple[str, ...], dict[str, dict]]:
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
        _Table(src, f"techniques.{name}", params, tuple(p.name for p in TECHNIQUES[name].params))
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
    _reject_non_finite(doc, src, "")
    root = _Table(src, "", doc, ("scene", "camera", "lights", "materials", "objects", "techniques"))
    section = _Table(src, "scene", doc.get("scene", {}), ("name", "technique", "techniques", "background"))
    technique, techniques, params = _techniques(root, section)

    raw_lights = root.array_of_tables("lights")
    if len(raw_lights) > MAX_LIGHTS:
        raise UserError(f"{src}: lights: {len(raw_lights)} [[lights]] tables; expected at most {MAX_LIGHTS} "
                        "(merge lights of the same direction, or drop the faintest)")
    lights = tuple(_light(src, f"lights[{i}]", x) for i, x in enumerate(raw_lights))
    materials = {
        name: _material(src, name, data, base) for name, data in root.table_of_tables("materials").items()
    }
    root.get("objects", _MISSING, "at least one [[objects]] table")
    raw_objects = root.array_of_tables("objects")
    if not raw_objects:
        raise root.error("objects", raw_objects, "expected at least one [[objects]] table")
    objects = tuple(_object(src, f"objects[{i}]", x, materials, base) for i, x in enumerate(raw_objects))
    camera = _camera(root)
    _check_geometry(src, camera, objects, raw_objects)

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
