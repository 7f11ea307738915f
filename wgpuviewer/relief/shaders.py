"""Technique shader modules: what the registry generates, composed with the technique's WGSL file.

A module = the generated interface (``interface``: the technique's ``TraceParams`` struct, its ``NAME_MIN`` /
``NAME_MAX`` parameter constants, ``MAX_LAYERS``, and the @group(1) binding lines of the uniform, the sampler and
every texture slot it needs) + the technique's file (``Technique.wgsl_file``, in its folder, with what it includes from
``wgsl/common/``) + for rendering and the filter probe the texture filter (``filters.filter_interface`` and
``wgsl/filters/NAME.wgsl``, with a visibility snippet for the texel-loop filters) + for rendering a derivative source
(``wgsl/derivatives/``) and a shading-normal snippet + an entry-point file (``entry/render.wgsl``, ``entry/probe.wgsl`` or
``entry/filter_probe.wgsl``), composed by ``wgpuviewer.core.wgsl`` (includes, line map for error locations).
Only the draw's filter and derivative source are compiled. A render module is also one material variant
(``MaterialVariant``, ``material_variant``): its shadow snippet (``shadows/off|hard|soft.wgsl``: only a shadowing
variant compiles shadow code), its addressing (``RELIEF_CLAMP``) and the technique's code paths the material runs
(``USES_NAME`` constants: auto compiles only the methods its table picks for the material); the shadow constants
come from the float64 reference (``reference.SHADOW_TOLERANCE_TEXELS`` ...), so both test one definition.
"""

from __future__ import annotations

from dataclasses import dataclass

from wgpuviewer.core.structs import Struct, array, range_constants, scalar_uniform
from wgpuviewer.core.wgsl import Generated, Module, compose
from wgpuviewer.scene import MAX_LIGHTS
from wgpuviewer.techniques import MAX_LAYERS, Technique

from .filters import DEFAULT_DERIVATIVES, DEFAULT_FILTER, filter_interface, get_derivatives, get_filter
from .maps import MAP_SLOTS, PARAMS_BINDING, SAMPLER_BINDING, binding
from .reference import SHADOW_TOLERANCE_TEXELS, SOFT_SHADOW_PENUMBRA, SOFT_SHADOW_SAMPLES

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
    # xy: Material.uv_scale (texture repeats across the face); zw: the fraction of Material.uv_offset, its whole
    # tiles dropped in float64 (repeat addressing: the same texture), so the uv the GPU interpolates stays small
    ("uv_transform", "vec4f"),
])


@dataclass(frozen=True)
class MaterialVariant:
    """What a material changes in its render module and pipeline: ``shadows`` (scene.SHADOW_MODES: the shadow
    snippet compiled in), ``depth_offset`` (the entry points that write the hit's depth) and ``clamp`` (clamp
    addressing: the uv square is the relief's extent, rays leaving it are discarded). The default is the plain
    module every scene without those keys draws."""

    shadows: str = "off"
    depth_offset: bool = False
    clamp: bool = False
    #: The technique's code paths compiled in (``Technique.code_paths``, from its ``paths_used`` for the material:
    #: auto's, the methods its table picks); None: all of them.
    paths: tuple[str, ...] | None = None

    @property
    def label(self) -> str:
        """'' for the plain variant, else e.g. '+shadows=hard+depth_offset+clamp+paths=pom,relief' (pipeline labels,
        created)."""
        parts = ([f"shadows={self.shadows}"] if self.shadows != "off" else []) + \
            (["depth_offset"] if self.depth_offset else []) + (["clamp"] if self.clamp else []) + \
            ([f"paths={','.join(self.paths)}"] if self.paths is not None else [])
        return "".join(f"+{p}" for p in parts)


PLAIN = MaterialVariant()


def material_variant(technique: Technique, material, params: dict, shadows: str, depth_offset: bool) -> MaterialVariant:
    """The variant ``material`` (a scene material) is drawn with by ``technique`` at ``params``: ``shadows`` and
    ``depth_offset`` (the draw's or the material's) only where the technique traces the relief, the material's
    addressing, and the technique's code paths it runs (``Technique.paths_used``)."""
    traced = traces_relief(technique)
    paths = technique.paths_used(material, params) if technique.paths_used is not None else None
    return MaterialVariant(shadows if traced else "off", depth_offset and traced, material.address == "clamp", paths)


def path_constants(technique: Technique, variant: MaterialVariant) -> Generated:
    """``const USES_NAME: bool`` for each of the technique's code paths: true where the variant compiles it in."""
    lines = [f"const USES_{name.upper()}: bool = {str(variant.paths is None or name in variant.paths).lower()};"
             for name in technique.code_paths]
    return Generated("<generated: code paths>", "\n".join(lines) + "\n")


def shadow_constants() -> list[str]:
    """The shadow definition's constants (reference.py) as WGSL (common/shadow.wgsl uses them)."""
    return [f"const SHADOW_TOLERANCE_TEXELS: f32 = {SHADOW_TOLERANCE_TEXELS!r};",
            f"const SOFT_SHADOW_SAMPLES: u32 = {SOFT_SHADOW_SAMPLES}u;",
            f"const SOFT_SHADOW_PENUMBRA: f32 = {SOFT_SHADOW_PENUMBRA!r};"]


def trace_params(technique: Technique) -> Struct:
    """The technique's TraceParams uniform: ``Technique.trace_field_types`` in order (counts and flags u32, signed
    integers i32, real numbers f32), padded to 16 bytes."""
    return scalar_uniform("TraceParams", technique.trace_field_types)


def interface(technique: Technique, entry: str) -> Generated:
    """The WGSL a technique's module must agree on with Python, generated from its registry entry."""
    lines = [f"// Generated from the registry entry of technique {technique.name!r} (wgpuviewer/relief).",
             trace_params(technique).wgsl().rstrip("\n"), f"const MAX_LAYERS: u32 = {MAX_LAYERS}u;",
             *range_constants(technique.params)]
    if entry == "render":
        lines += [f"const MAX_LIGHTS: u32 = {MAX_LIGHTS}u;", FRAME.wgsl_all().rstrip("\n"),
                  OBJECT.wgsl().rstrip("\n")]
    if entry in ("render", "shadow_probe"):
        lines += shadow_constants()
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
                      derivatives: str = DEFAULT_DERIVATIVES, records: tuple[Generated, ...] = (),
                      variant: MaterialVariant = PLAIN) -> Module:
    """The module for ``technique`` with entry point file ``entry/ENTRY.wgsl`` ('render', 'probe', 'shadow_probe'
    or 'filter_probe'); ``filter`` and ``derivatives`` name the texture filter and derivative source (render),
    ``variant`` the material variant (shadows, for render, need a technique that traces the relief:
    ``traces_relief``; its code paths apply to every entry, the probe's default being all of them).
    ``records``: the entry's own records, generated by the Python side that fills or reads them (the probe's
    rays and hits, the render targets' ``DataOut``), which the entry file uses and does not declare."""
    parts = [interface(technique, entry), path_constants(technique, variant), technique.wgsl_file]
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
        if variant.shadows != "off" and not traces_relief(technique):
            raise ValueError(f"technique {technique.name!r} does not trace the relief: no shadows to draw")
        parts += [f"shadows/{variant.shadows}.wgsl",
                  Generated("<generated: material variant>", f"const RELIEF_CLAMP: bool = {str(variant.clamp).lower()};\n")]
    parts += [*records, f"entry/{entry}.wgsl"]
    return compose(*parts)


def trace_params_size(technique: Technique) -> int:
    return trace_params(technique).size


def pack_trace_params(technique: Technique, height_scale: float, depth_shape: tuple, params: dict,
                      depth_range: tuple[float, float] = (0.0, 1.0)) -> bytes:
    """TraceParams uniform data for ``technique``, each value in its field's type (booleans as 0/1).
    ``params`` holds the parameter values (missing ones take the registry defaults); ``depth_range`` is the depth
    map's (maps.depth_range; the default claims nothing about the map)."""
    values = {**technique.defaults(), **params, **technique.fixed_values(),
              "height_scale": height_scale, "depth_width": depth_shape[1], "depth_height": depth_shape[0],
              "depth_min": depth_range[0], "depth_max": depth_range[1]}
    return trace_params(technique).pack({name: values[name] for name in technique.trace_fields})
