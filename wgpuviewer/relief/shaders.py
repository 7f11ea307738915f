"""Technique shader modules: what the registry generates, composed with the technique's WGSL file.

A module = the generated interface (``interface``: the technique's ``TraceParams`` struct, its ``NAME_MIN`` /
``NAME_MAX`` parameter constants, ``MAX_LAYERS``, and the @group(1) binding lines of the uniform, the sampler and
every texture slot it needs) + the technique's file (with what it includes from ``wgsl/common/``) + for rendering
and the filter probe the texture filter (``filters.filter_interface`` and ``wgsl/filters/NAME.wgsl``, with a
visibility snippet for the texel-loop filters) + for rendering a derivative source (``wgsl/derivatives/``) and a
shading-normal snippet + an entry-point file (``entry/render.wgsl``, ``entry/probe.wgsl`` or
``entry/filter_probe.wgsl``), composed by ``wgpuviewer.core.wgsl`` (includes, line map for error locations).
Only the draw's filter and derivative source are compiled.
"""

from __future__ import annotations

from wgpuviewer.core.structs import Struct, array, f32_uniform, range_constants
from wgpuviewer.core.wgsl import Generated, Module, compose
from wgpuviewer.scene import MAX_LIGHTS

from .filters import DEFAULT_DERIVATIVES, DEFAULT_FILTER, filter_interface, get_derivatives, get_filter
from .maps import MAP_SLOTS, PARAMS_BINDING, SAMPLER_BINDING, binding
from .techniques import MAX_LAYERS, Technique

#: The render entry's uniforms (``entry/render.wgsl``): group 0's Frame (camera, view mode, lights; MAX_LIGHTS, the
#: scene format's limit, sizes its light array) and group 2's Object, generated into the render interface.
LIGHT = Struct("Light", [
    ("vector", "vec4f"),  # w = 0: direction towards the light; w = 1: light position
    ("color", "vec4f"),  # rgb * intensity
])
FRAME = Struct("Frame", [
    ("view_proj", "mat4x4f"),
    ("camera_pos", "vec4f"),
    ("light_count", "u32"),
    ("mode", "u32"),  # render.wgsl's MODE_* constants
    ("cost_scale", "f32"),  # fetch count shown as full heat in MODE_COST (Technique.cost_scale)
    ("layer_lo", "f32"),  # MODE_LAYERS grey: (N - layer_lo) / (layer_hi - layer_lo) (Technique.layer_range)
    ("layer_hi", "f32"),
    ("lights", array(LIGHT, MAX_LIGHTS)),
])
OBJECT = Struct("Object", [
    ("model", "mat4x4f"),
    ("normal_matrix", "mat4x4f"),
    ("uv_scale", "vec4f"),  # xy: texture repeats across the face
])


def trace_params(technique: Technique) -> Struct:
    """The technique's TraceParams uniform: ``Technique.trace_fields`` in order, padded to 16 bytes. Every field
    is f32, counts and flags too: the technique WGSL files convert them where they use them."""
    return f32_uniform("TraceParams", technique.trace_fields)


def interface(technique: Technique, entry: str) -> Generated:
    """The WGSL a technique's module must agree on with Python, generated from its registry entry."""
    lines = [f"// Generated from the registry entry of technique {technique.name!r} (wgpuviewer/relief).",
             trace_params(technique).wgsl().rstrip("\n"), f"const MAX_LAYERS: u32 = {MAX_LAYERS}u;",
             *range_constants(technique.params)]
    if entry == "render":
        lines += [f"const MAX_LIGHTS: u32 = {MAX_LIGHTS}u;", FRAME.wgsl_all().rstrip("\n"),
                  OBJECT.wgsl().rstrip("\n")]
    lines += [f"@group(1) @binding({PARAMS_BINDING}) var<uniform> trace_params: TraceParams;",
              f"@group(1) @binding({SAMPLER_BINDING}) var material_sampler: sampler;"]
    for name in technique.textures:
        slot = MAP_SLOTS[name]
        lines += [f"// {name}: {slot.doc}",
                  f"@group(1) @binding({binding(name)}) var {slot.wgsl_name}: {slot.wgsl_type};"]
    return Generated(f"<generated: {technique.name} interface>", "\n".join(lines) + "\n")


def traces_relief(technique: Technique) -> bool:
    """Whether the technique's hit depends on a depth map (then footprints can be displaced and texels hidden)."""
    return technique.ray_search and technique.needs_depth


def compose_technique(technique: Technique, entry: str, filter: str = DEFAULT_FILTER,
                      derivatives: str = DEFAULT_DERIVATIVES) -> Module:
    """The module for ``technique`` with entry point file ``entry/ENTRY.wgsl`` ('render', 'probe' or
    'filter_probe'); ``filter`` and ``derivatives`` name the texture filter and derivative source (render)."""
    parts = [interface(technique, entry), technique.wgsl_file]
    if entry in ("render", "filter_probe"):
        f = get_filter(filter)
        parts += [filter_interface(f), f.wgsl_file]
        if f.texel_loop:
            traced = f.visibility and traces_relief(technique)
            parts.append("visibility/traced.wgsl" if traced else "visibility/none.wgsl")
    if entry == "render":
        source = get_derivatives(derivatives)
        parts.append(source.wgsl_file if traces_relief(technique) or not source.traced else "derivatives/uv.wgsl")
        parts.append("shading/normal_from_map.wgsl" if "normal" in technique.textures else "shading/normal_flat.wgsl")
    parts.append(f"entry/{entry}.wgsl")
    return compose(*parts)


def trace_params_size(technique: Technique) -> int:
    return trace_params(technique).size


def pack_trace_params(technique: Technique, height_scale: float, depth_shape: tuple, params: dict,
                      depth_range: tuple[float, float] = (0.0, 1.0)) -> bytes:
    """TraceParams uniform data for ``technique`` (booleans as 0/1).
    ``params`` holds the parameter values (missing ones take the registry defaults); ``depth_range`` is the depth
    map's (maps.depth_range; the default claims nothing about the map)."""
    values = {**technique.defaults(), **params, **dict(technique.fixed),
              "height_scale": height_scale, "depth_width": depth_shape[1], "depth_height": depth_shape[0],
              "depth_min": depth_range[0], "depth_max": depth_range[1]}
    return trace_params(technique).pack({name: float(values[name]) for name in technique.trace_fields})
