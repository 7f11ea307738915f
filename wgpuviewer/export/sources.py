"""The exported module's bindings and its header: what each binding holds and which command makes it.

A texture slot's map comes from where its slot is declared (``relief.maps.MAP_SLOTS``, found by the module of its
build function): the depth map from the height map itself, a map kind's from ``maptools`` (``maptools batch
--kinds KIND`` writes ``STEM.KIND.EXT``, the kind's first extension), a technique's own from that technique. As the
trace binds it (packed, in its format, with its levels) ``wgpuviewer export ... --maps HEIGHT`` writes every one to
``STEM.SLOT.texture.npz`` (``textures.py``), next to the names ``maptools batch`` gives its maps.

May import: ``wgpuviewer.core``, the technique registry, ``wgpuviewer.relief`` (the slot table) and maptools' kind
registry; never the lab.
"""

from __future__ import annotations

from maptools.registry import KINDS
from wgpuviewer.core.structs import Struct
from wgpuviewer.relief.maps import MAP_SLOTS
from wgpuviewer.techniques import Technique

#: Suffix of a texture file ``--maps`` writes: STEM.SLOT.texture.npz (a map kind's own file is STEM.KIND.EXT).
TEXTURE_SUFFIX = ".texture.npz"

#: What the uniform's common fields hold (the registry's COMMON_TRACE_FIELDS).
FIELD_DOCS = {
    "height_scale": "relief depth in UV units (the depth of t = 1 below the surface)",
    "depth_width": "the depth texture's width in texels (level 0)",
    "depth_height": "the depth texture's height in texels (level 0)",
    "depth_min": "lowest depth D in the map (minus 2^-10), or 0.0: layer searches march [depth_min, depth_max]",
    "depth_max": "highest depth D in the map (plus 2^-10), or 1.0",
}


def texture_file(stem: str, slot: str) -> str:
    """The file name ``--maps`` writes a slot's texture to, for a height map named ``stem``."""
    return f"{stem}.{slot}{TEXTURE_SUFFIX}"


def made_by(slot: str) -> str:
    """Where the slot's map comes from, with the command that makes it."""
    parts = MAP_SLOTS[slot].build.__module__.split(".")
    if parts[:2] == ["maptools", "kinds"]:
        kind = parts[2]
        ext = KINDS[kind].extensions[0]
        return (f"maptools' {kind} map: `maptools batch --kinds {kind} HEIGHT -o DIR` writes DIR/STEM.{kind}{ext}")
    if parts[:2] == ["wgpuviewer", "techniques"]:
        return f"technique {parts[2]}'s own data, measured on the height map"
    return "the height map H itself, as 1 - H"


def binding_lines(technique: Technique, group: int, slots: list[str]) -> list[str]:
    """The uniform, the sampler and the texture bindings (the composer's names; the export prefixes them)."""
    lines = [f"@group({group}) @binding(0) var<uniform> relief_params: ReliefParams;",
             f"@group({group}) @binding(1) var material_sampler: sampler;"]
    for index, name in enumerate(slots):
        slot = MAP_SLOTS[name]
        lines.append(f"@group({group}) @binding({2 + index}) var {slot.wgsl_name}: {slot.wgsl_type};")
    return lines


def header(technique: Technique, constants: dict, uniforms: list[str], group: int, params: Struct,
           slots: list[str], command: str) -> str:
    """The module's leading comment: what it is, its API, its parameters and each binding."""
    lines = [
        f"// Relief tracing with technique '{technique.name}', exported from wgpuviewer"
        + (f" by `{command}`." if command else "."),
        f"// {technique.description}",
        "//",
        "// fn relief_trace(uv: vec2f, view_ts: vec3f, lod: f32) -> ReliefHit",
        "//   uv: where the view ray enters the relief's top (z = 0); view_ts: V, the unit vector from the surface",
        "//   towards the eye in tangent space (x = u, y = v, z = the normal); lod: the mip level of depth fetches.",
        "//   ReliefHit: uv (where the ray meets the relief; not wrapped), depth (layer depth t: 0 = top, 1 = height_scale",
        "//   below), fetches (depth texels read), capped (a cap or a grazing view decided it: do not trust it), layers.",
        "//   The ray: uv(t) = uv - t * V.xy / V.z * height_scale. The depth map holds D = 1 - height.",
        "//",
        "// Parameters (constants): " + (", ".join(f"{k} = {v}" for k, v in constants.items()) or "none"),
    ]
    if uniforms:
        lines.append("// Parameters read from the uniform: " + ", ".join(uniforms))
    lines += [f"// Bindings, @group({group}):",
              f"//   @binding(0) relief_params: ReliefParams, uniform, {params.size} bytes:"]
    for name, wgsl_type in params.fields:
        if not name.startswith("_"):
            doc = FIELD_DOCS.get(name) or technique.param(name).doc
            lines.append(f"//     {name}: {wgsl_type} at byte {params.offsets[name]}: {doc}")
    lines.append("//   @binding(1) relief_material_sampler: sampler, linear min and mag filtering, repeat addressing "
                 "(clamp_to_edge for a relief that does not tile)")
    for index, name in enumerate(slots):
        slot = MAP_SLOTS[name]
        lines += [f"//   @binding({2 + index}) relief_{slot.wgsl_name}: {slot.wgsl_type}: {slot.doc}",
                  f"//     made from {made_by(name)}"
                  + ("; built for the material's height_scale, so the uniform's must equal it" if slot.scale_bound else ""),
                  f"//     as bound here: `wgpuviewer export {technique.name} --maps HEIGHT` writes "
                  f"{texture_file('STEM', name)}"]
    return "\n".join(lines) + "\n\n"
