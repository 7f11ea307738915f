"""One self-contained WGSL module for a ray-search technique, to run in someone else's renderer.

``export_wgsl`` composes the technique's ``trace`` through the project's one composer (``relief.shaders`` and
``core.wgsl``: what the probe compiles, includes resolved, the technique's generated constants, without the probe's
entry point and bindings), then wraps it in the module's API::

    struct ReliefHit { uv: vec2f, depth: f32, fetches: u32, capped: bool, layers: u32 }
    fn relief_trace(uv: vec2f, view_ts: vec3f, lod: f32) -> ReliefHit

The technique's ``TraceParams`` becomes a private value that ``relief_trace`` fills on entry: the material's values
(relief depth, depth map size and range) from the uniform ``relief_params: ReliefParams`` at binding 0, the
parameters as constants (or from the uniform too: ``uniform_params``), the fixed values as constants. The sampler
and the technique's height-derived textures follow at bindings 1, 2, ... of ``@group(N)``. Every module-scope name
gets the ``relief_``/``Relief``/``RELIEF_`` prefix (``rename``), so the module sits next to a user's own code.

May import: ``wgpuviewer.core``, the technique registry, ``wgpuviewer.relief`` (the composer's technique pieces and
the slot table) and maptools' kind registry (the commands that make the maps); never the lab.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.params import resolve_params
from wgpuviewer.core.structs import Struct, scalar_literal, scalar_uniform
from wgpuviewer.core.wgsl import Generated, compose
from wgpuviewer.relief.maps import MAP_SLOTS
from wgpuviewer.relief.shaders import compose_technique, trace_params
from wgpuviewer.techniques import COMMON_TRACE_FIELDS, TECHNIQUES, Technique, get_technique

from .rename import module_names, prefixed, rename
from .sources import binding_lines, header

#: The names the module exposes (kept as they are; everything else gets the prefix).
API = ("relief_trace", "ReliefHit", "ReliefParams", "relief_params")
#: The API's hit record; ``layers``: the depth layers the search used (0 for searches without layers).
HIT_FIELDS = (("uv", "vec2f"), ("depth", "f32"), ("fetches", "u32"), ("capped", "bool"), ("layers", "u32"))
#: The probe's entry file: what the export leaves out of the probe's module (with what only it includes).
ENTRY = "entry/probe.wgsl"
_BINDING = re.compile(r"^\s*@group\(\d+\)\s*@binding\(\d+\)")
#: Binding of the uniform and of the sampler in the chosen group; the textures follow.
PARAMS_BINDING, SAMPLER_BINDING, FIRST_TEXTURE_BINDING = 0, 1, 2


def exportable() -> list[str]:
    """The techniques ``export_wgsl`` takes: every ray search of the registry (the others have no ``trace``)."""
    return [name for name, t in TECHNIQUES.items() if t.ray_search]


def texture_slots(technique: Technique) -> list[str]:
    """The slots the trace samples, in binding order (2, 3, ...): the technique's height-derived textures."""
    return [name for name in technique.textures if MAP_SLOTS[name].derived]


def params_struct(technique: Technique, uniform_params: bool) -> Struct:
    """The ``ReliefParams`` uniform: the material's fields (the registry's common ones), then the parameters when
    they stay uniforms, each in its WGSL type, padded to 16 bytes."""
    fields = list(COMMON_TRACE_FIELDS) + ([(p.name, p.wgsl_type) for p in technique.params] if uniform_params else [])
    return scalar_uniform("ReliefParams", fields)


@dataclass(frozen=True)
class Export:
    """What ``export_wgsl`` made: the technique, its parameter values, the group, the uniform and the code."""

    technique: Technique
    values: dict
    group: int
    params: Struct
    code: str

    @property
    def textures(self) -> list[str]:
        return texture_slots(self.technique)


def traced_code(technique: Technique) -> str:
    """What the probe compiles of the technique (``relief.shaders.compose_technique``: the generated interface and
    constants, the technique's file and its includes), without the probe's entry point, the files only that entry
    includes, and the interface's bindings (the export declares its own)."""
    probe = compose_technique(technique, "probe")
    entry_only = set(compose(ENTRY).files) - set(compose(technique.wgsl_file).files)
    slot_notes = tuple(f"// {name}: " for name in technique.textures)  # the dropped binding lines' comments
    return "\n".join(line for line, (origin, _) in zip(probe.code.splitlines(), probe.lines)
                     if origin not in entry_only and not _BINDING.match(line) and not line.startswith(slot_notes)) + "\n"


def _fill(technique: Technique, values: dict, uniform_params: bool) -> str:
    """The TraceParams constructor ``relief_trace`` fills the private value with, field by field."""
    params = {p.name for p in technique.params}
    fixed = technique.fixed_values()
    args = []
    for name, wgsl_type in trace_params(technique).fields:
        if name in dict(COMMON_TRACE_FIELDS) or (name in params and uniform_params):
            args.append(f"relief_params.{name}")
        elif name in params:
            args.append(scalar_literal(int(values[name]) if wgsl_type != "f32" else values[name], wgsl_type))
        elif name in fixed:
            args.append(scalar_literal(fixed[name], wgsl_type))
        else:  # the uniform's padding
            args.append(scalar_literal(0, wgsl_type))
    return "TraceParams(" + ", ".join(args) + ")"


def _api(technique: Technique, values: dict, uniform_params: bool) -> str:
    return "\n".join([
        "struct ReliefHit {", *(f"    {n}: {t}," for n, t in HIT_FIELDS), "}",
        "",
        "// The trace's parameters: filled on every entry (constants fold; the material's values from the uniform).",
        "var<private> trace_params: TraceParams;",
        "",
        "fn relief_trace(uv: vec2f, view_ts: vec3f, lod: f32) -> ReliefHit {",
        f"    trace_params = {_fill(technique, values, uniform_params)};",
        "    let r = trace(uv, view_ts, lod);",
        "    return ReliefHit(r.uv, r.depth, r.fetches, r.capped, r.layers);",
        "}",
    ]) + "\n"


def export_wgsl(name: str, settings: dict | None = None, group: int = 1, uniform_params: bool = False,
                command: str = "") -> Export:
    """The module for technique ``name`` with parameter ``settings`` (checked against the registry; the defaults
    for the rest) at ``@group(group)``. ``command``: the command line the header records."""
    technique = get_technique(name)
    if not technique.ray_search:
        raise UserError(f"technique {name!r} traces no rays, so it has no relief_trace to export; "
                        f"exportable: {', '.join(exportable())}")
    if not 0 <= group <= 3:
        raise UserError(f"--group {group}: expected a bind group from 0 to 3 (WebGPU's default limit of 4 groups)")
    values = resolve_params(technique, settings, where="--set ")
    params = params_struct(technique, uniform_params)
    uniforms = {p.name for p in technique.params} if uniform_params else set()
    interface = Generated(f"<export: {technique.name} bindings>", "\n".join([
        params.wgsl().rstrip("\n"), *binding_lines(technique, group, texture_slots(technique))]) + "\n")
    module = compose(interface, Generated("<export: trace>", traced_code(technique)),
                     Generated("<export: api>", _api(technique, values, uniform_params)))
    names = [n for n in module_names(module.code) if n not in API]
    mapping = {n: prefixed(n, set(API)) for n in names}
    text = header(technique, {k: v for k, v in values.items() if k not in uniforms}, sorted(uniforms), group, params,
                  texture_slots(technique), command) + rename(module.code, mapping)
    return Export(technique, values, group, params, text)
