"""A scene's ``[materials.NAME]`` tables read into ``Material``: texture values (builtin, file, RGB colour; a file's
header read at once so a bad file is reported against its key), ``folder = "DIR"`` (``folders``), the precomputed
maps a material names (``[materials.X.maps]``, ``NAMED_MAPS``, each checked against its height file's record).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from wgpuviewer.core.errors import FileError
from wgpuviewer.core.images import read_header
from wgpuviewer.core.sidecar import file_sha256, read_record
from wgpuviewer.textures import BUILTINS, MAX_BUILTIN_SIZE, TextureRef

from .folders import FOLDER_SLOTS, folder_refs, report_folder
from .limits import texel_coordinate_problem
from .model import ADDRESS_MODES, CHANNELS, SHADOW_MODES, Material
from .table import MISSING, Table, show_value

_TEXTURE_FORMS = "'builtin:NAME', { builtin = NAME, size = [W, H] } or a file path"


def _texture(t: Table, name: str, base: Path, color_ok: bool = False, required: bool = False) -> TextureRef | None:
    """A texture value (builtin, file or, where ``color_ok``, an RGB array); None when absent. A file's header is
    read here (format, size, limits: cheap), so a bad file is reported at once against its key."""
    expected = _TEXTURE_FORMS + (" or an RGB array [r, g, b]" if color_ok else "")
    value = t.get(name, MISSING if required else None, f"a texture: {expected}")
    if value is None:
        return None
    origin = f"{t.src}: {t.path(name)} = {show_value(value)}"
    if isinstance(value, list) and color_ok:
        return TextureRef("color", color=t.vector(name, 3, lo=0, hi=1), origin=origin)
    if isinstance(value, dict):
        spec = Table(t.src, t.path(name), value, ("builtin", "size"))
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
    return _file_ref(t, name, value, t.file_path(name, value, base))


def _file_ref(t: Table, name: str, value, path: Path) -> TextureRef:
    """A file texture at ``path`` named by key ``name`` (value ``value``), its header checked."""
    if not path.exists():
        raise t.error(name, value, f"file not found (looked for {path})")
    try:
        read_header(path)
    except FileError as error:
        raise t.error(name, value, error.reason) from None
    return TextureRef("file", path=path, origin=f"{t.src}: {t.path(name)} = {show_value(value)}")


def _builtin_ref(t: Table, key: str, value: str, size: tuple[int, int], origin: str) -> TextureRef:
    name = value.removeprefix("builtin:")
    if name not in BUILTINS:
        raise t.error(key, value, f"unknown builtin texture; expected one of {', '.join(BUILTINS)}")
    return TextureRef("builtin", name=name, size=size, origin=origin)


def read_material(src: str, name: str, data, base: Path) -> Material:
    """The ``[materials.NAME]`` table ``data`` as a Material; its files relative to ``base``."""
    t = Table(src, f"materials.{name}", data,
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
    problem = texel_coordinate_problem(uv_scale, (albedo, normal, height))
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


def _named_maps(t: Table, base: Path, height: TextureRef | None, is_depth: bool) -> tuple[tuple[str, TextureRef], ...]:
    """``[materials.X.maps]`` SLOT = "FILE" (relative to the scene): each file's batch record (core.sidecar) must say
    it is a map of that slot built from the material's height file (the same bytes, read through the same channel).
    The renderer checks the rest (options, maptools version, the file's own bytes) when it serves the map."""
    raw = t.get("maps", None, "")
    if raw is None:
        return ()
    maps = Table(t.src, t.path("maps"), raw, NAMED_MAPS)
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
        path = maps.file_path(slot, value, base)
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
        named.append((slot, TextureRef("file", path=path, origin=f"{t.src}: {maps.path(slot)} = {show_value(value)}")))
    return tuple(named)


def _folder(t: Table, base: Path) -> dict | None:
    """``folder = "DIR"``: the material's files found by name (folders.find_material_files); None if absent."""
    value = t.get("folder", None, "a folder path")
    if value is None:
        return None
    if not isinstance(value, str):
        raise t.error("folder", value, "expected a folder path (a string)")
    path = t.file_path("folder", value, base)
    if not path.exists():
        raise t.error("folder", value, f"folder not found (looked for {path})")
    # keys given next to the folder win: the folder is not searched for their slots (depth fills the height's)
    named = [slot for slot in FOLDER_SLOTS if slot in t.data or (slot == "height" and "depth" in t.data)]
    try:
        return folder_refs(path, f"{t.src}: {t.path('folder')} = {show_value(value)}", named)
    except FileError as error:
        raise t.error("folder", value, error.reason) from None
