"""The technique registry: one entry per WGSL file in ``wgsl/``.

An entry names what a technique needs (textures/maps), its parameters with defaults and ranges,
and whether it is a ray search (then its WGSL defines ``trace`` and the probe can run it).
Parameters travel to WGSL in the ``TraceParams`` uniform, whose struct is generated from
``TRACE_FIELDS`` so Python packing and WGSL layout cannot drift apart.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .errors import UserError

#: Fields of the WGSL ``TraceParams`` uniform (all f32, in this order). ``height_scale`` and the
#: depth map's size in texels (for the mip level) come from the material; the rest are technique
#: parameters (0 where a technique has no such parameter).
TRACE_FIELDS = ("height_scale", "depth_width", "depth_height", "layers", "offset_limiting")

#: Hard cap on any layer count, mirrored by ``MAX_LAYERS`` in the WGSL prelude.
MAX_LAYERS = 1024


@dataclass(frozen=True)
class Param:
    name: str
    default: float
    min: float
    max: float
    kind: type  # int, float or bool
    doc: str

    def validate(self, value, where: str):
        """Checked value, or UserError naming ``where`` (e.g. 'scene.toml: techniques.pom.layers')."""
        expected = {int: "an integer", float: "a number", bool: "true or false"}[self.kind]
        ok_type = isinstance(value, bool) if self.kind is bool else (
            isinstance(value, int) and not isinstance(value, bool)
            if self.kind is int
            else isinstance(value, (int, float)) and not isinstance(value, bool)
        )
        if not ok_type:
            raise UserError(f"{where} = {value!r}: expected {expected}")
        if self.kind is not bool and not (self.min <= value <= self.max):
            raise UserError(f"{where} = {value!r}: out of range, expected {self.min:g} to {self.max:g}")
        return self.kind(value)


@dataclass(frozen=True)
class Technique:
    name: str
    key: str  # default keyboard key in the viewer
    description: str
    cost: str  # what it costs, for humans (README table, `wgpuviewer techniques`)
    textures: tuple[str, ...]  # of 'albedo', 'normal', 'depth'
    params: tuple[Param, ...] = ()
    ray_search: bool = False
    wgsl: str = field(default="")

    @property
    def wgsl_file(self) -> str:
        return self.wgsl or f"{self.name}.wgsl"

    @property
    def needs_depth(self) -> bool:
        return "depth" in self.textures

    def param(self, name: str) -> Param:
        for p in self.params:
            if p.name == name:
                return p
        raise KeyError(name)

    def defaults(self) -> dict:
        return {p.name: p.kind(p.default) for p in self.params}


_LAYERS_DOC = "layer count: the ray is tested at this many evenly spaced depths (cap: MAX_LAYERS)"

TECHNIQUES: dict[str, Technique] = {
    t.name: t
    for t in (
        Technique(
            "basic", "1", "Basic texturing: albedo at the interpolated UV, flat surface normal.",
            "1 albedo fetch", ("albedo",),
        ),
        Technique(
            "normal", "2", "Normal mapping: per-pixel normals from the normal map, no displacement.",
            "albedo + normal fetch", ("albedo", "normal"),
        ),
        Technique(
            "parallax", "3",
            "Parallax (offset) mapping: uv' = uv - V.xy/V.z * depth(uv) * scale; with offset limiting "
            "the division by V.z is dropped (Welsh), which bounds the offset at grazing angles.",
            "1 depth fetch", ("albedo", "normal", "depth"),
            (Param("offset_limiting", False, 0, 1, bool, "drop the 1/V.z factor (bounded offset)"),),
            ray_search=True,
        ),
        Technique(
            "steep", "4",
            "Steep parallax mapping: march N depth layers along the view ray, stop at the first layer "
            "below the surface.",
            "up to N+1 depth fetches", ("albedo", "normal", "depth"),
            (Param("layers", 16, 1, MAX_LAYERS, int, _LAYERS_DOC),),
            ray_search=True,
        ),
        Technique(
            "pom", "5",
            "Parallax occlusion mapping: steep parallax, then linear interpolation between the last two "
            "layers (guarded against a zero denominator).",
            "up to N+1 depth fetches", ("albedo", "normal", "depth"),
            (Param("layers", 16, 1, MAX_LAYERS, int, _LAYERS_DOC),),
            ray_search=True,
        ),
    )
}


def get_technique(name: str, where: str = "technique") -> Technique:
    try:
        return TECHNIQUES[name]
    except KeyError:
        raise UserError(f"{where} = {name!r}: unknown technique; expected one of {', '.join(TECHNIQUES)}") from None


def resolve_params(technique: Technique, overrides: dict | None = None, where: str = "") -> dict:
    """Defaults merged with checked overrides (unknown names are errors naming ``where``)."""
    values = technique.defaults()
    for name, value in (overrides or {}).items():
        key = f"{where}{name}" if where else f"{technique.name}.{name}"
        try:
            param = technique.param(name)
        except KeyError:
            known = ", ".join(p.name for p in technique.params) or "none"
            raise UserError(f"{key}: unknown parameter of technique {technique.name!r}; known: {known}") from None
        values[name] = param.validate(value, key)
    return values
