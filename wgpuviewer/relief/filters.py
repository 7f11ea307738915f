"""The texture-filter registry: one entry per WGSL file in ``wgsl/filters/``, and the derivative sources.

A filter decides how the albedo and the normal map are read at the traced hit (``entry/render.wgsl`` calls its
``filter_texture`` for both): from one texel (``nearest``) to an elliptical weighted average over the pixel's
footprint that drops the texels the relief hides (``ewa_vis``, after Romanyuk & Dudnyk 2017, filtering with parallax
mapping). A derivative source decides which footprint the filter is given: the derivatives of the unperturbed
surface uv (the default), of the traced hit uv, or the hit's local Jacobian. Everything WGSL must agree on is
generated from these entries (``filter_interface``): the ``FilterParams`` uniform (the filter's parameters, each of
its own WGSL type, padded), ``NAME_MIN`` / ``NAME_MAX`` constants for them in that type, the stat flags, the
visibility tolerance and the derivative bound. The renderer makes the filter's sampler from ``Filter.sampler``
(WebGPU allows anisotropy only with linear min, mag and mipmap filters).
"""

from __future__ import annotations

from dataclasses import dataclass

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.params import Param, Parametrized, resolve_params
from wgpuviewer.core.structs import Struct, f32_literal, range_constants, scalar_uniform
from wgpuviewer.core.wgsl import Generated

#: The default filter and derivative source: hardware trilinear on the unperturbed uv: the plain hardware lookup.
DEFAULT_FILTER = "trilinear"
DEFAULT_DERIVATIVES = "uv"

#: A texel is hidden when the view ray towards it first meets the relief this much (layer depth) before it.
VIS_TOLERANCE = 1e-2
#: Displaced and analytic derivatives longer than this many times the unperturbed ones are scaled down to it
#: (and the pixel flagged): at depth discontinuities the traced uv jumps, and so would the footprint.
DERIVATIVE_LIMIT = 8.0

#: The bind group of the filter's uniform and sampler (the renderer's groups 0-2 are frame, material, object).
FILTER_GROUP = 3

#: Bits of the per-pixel filter flags (the `filter` data target's z >> 24, the filter probe's flags).
FLAGS = {
    "capped": 1,  # the texel cap raised the mip level or ended the loop
    "nonfinite": 2,  # a NaN/inf derivative or uv was replaced (zero footprint / uv 0)
    "huge": 4,  # a derivative longer than the texture was shortened to it
    "bounded": 8,  # the derivative source's bound (DERIVATIVE_LIMIT) applied
    "vis_capped": 16,  # a visibility trace hit its cap (the texel was kept)
}


@dataclass(frozen=True)
class Filter(Parametrized):
    name: str
    description: str
    cost: str  # what it reads per lookup, for humans (`wgpuviewer filters`, the README)
    sampler: tuple[str, str, str]  # mag, min, mipmap filter of its sampler ("nearest" | "linear")
    params: tuple[Param, ...] = ()
    #: Reads texels itself (textureLoad) in a loop over the footprint, instead of one hardware sample.
    texel_loop: bool = False
    #: Drops footprint texels that the relief hides (traces the view ray towards each; needs a ray search).
    visibility: bool = False
    #: Takes derivatives: nearest and bilinear read level 0 and ignore them.
    uses_derivatives: bool = True
    #: Largest |GPU - float64 twin| of a filtered value on the same footprints (the twin:
    #: ``wgpuviewer.lab.studies.filtering.cpu.cpu_filter``; tests/relief/test_filters.py holds every filter to it).
    twin_tolerance: float | None = None
    #: Why the filter has no twin (then ``twin_tolerance`` is None): every filter has one or the other.
    no_twin: str = ""

    @property
    def wgsl_file(self) -> str:
        return f"filters/{self.name}.wgsl"

    @property
    def uniform_fields(self) -> tuple[tuple[str, str], ...]:
        """(name, WGSL type) of the FilterParams fields in order (``Param.wgsl_type``), without padding."""
        return tuple((p.name, p.wgsl_type) for p in self.params)


@dataclass(frozen=True)
class DerivativeSource:
    name: str
    description: str
    #: Needs the traced relief (a depth-tracing technique); without one it is the unperturbed source.
    traced: bool = True

    @property
    def wgsl_file(self) -> str:
        return f"derivatives/{self.name}.wgsl"


_LINEAR = ("linear", "linear", "linear")
#: Gaussian sharpness. 4: the best against the box reference on the filtering study's tuning cases, which never
#: rank the filters (docs/filtering.md); 6: the weights' variance is a one-pixel box's (1/12 pixel^2); 2 (Heckbert,
#: pbrt): sigma 1/2 pixel, smoother, more blur (the best against the Gaussian reference).
_ALPHA = Param("alpha", 4.0, 1.6, 8.0, float, "Gaussian sharpness: weight exp(-alpha r^2) - exp(-alpha), r in "
               "pixels (4: tuned against the box reference; 6: the variance of a one-pixel box; 2: sigma 1/2 pixel)")
_MAX_TEXELS = Param("max_texels", 256, 4, 4096, int,
                    "texel cap per lookup: a larger footprint is read from a coarser level (flagged capped)")
#: The visibility filters' weighting of a hidden texel: dropped (0), or inherited by its substitute (1).
_INHERIT = Param("inherit", 0, 0, 1, int,
                 "a hidden texel's weight: 0 dropped (the visible texels renormalised), 1 inherited by its "
                 "substitute, the texel its ray meets, when that lies outside the footprint (one inside is counted "
                 "once, by the walk)")
FILTERS: dict[str, Filter] = {
    f.name: f
    for f in (
        Filter("nearest", "The texel the hit falls in, level 0: no filtering at all.", "1 texel",
               ("nearest", "nearest", "nearest"), uses_derivatives=False, twin_tolerance=0.0),
        Filter("bilinear", "Hardware bilinear at level 0: no mip mapping, aliases under minification.", "4 texels",
               ("linear", "linear", "nearest"), uses_derivatives=False,
               twin_tolerance=5e-3),  # the sampler's fixed-point bilinear weights
        Filter("trilinear", "Hardware trilinear: mip level from the larger derivative, blended between two levels "
               "(the renderer's default).", "8 texels", _LINEAR,
               twin_tolerance=0.03),  # GPUs approximate the level formula
        Filter("aniso", "Hardware anisotropic filtering (textureSampleGrad on a sampler with max_anisotropy; "
               "the probe pattern is the driver's).", "up to 8 x max_anisotropy texels (driver-defined)", _LINEAR,
               (Param("max_anisotropy", 16, 2, 16, int, "the sampler's max_anisotropy (WebGPU: 1 to 16)"),),
               no_twin="the driver picks the anisotropic probes and their weights; no float64 model predicts them"),
        Filter("ewa", "Elliptical weighted average (Heckbert): Gaussian weights over the footprint ellipse from the "
               "derivatives (plus the bilinear tent's variance as prefilter), read where the minor axis spans 2-4 "
               "texels, two levels blended; a texel cap.", "pi * major * minor / 4^level texels, at most max_texels",
               _LINEAR,
               (_MAX_TEXELS, _ALPHA), texel_loop=True,
               twin_tolerance=1e-4),  # textureLoad texels: float32 arithmetic only
        Filter("ewa_approx", "EWA approximated by hardware trilinear probes along the major axis, Gaussian-weighted, "
               "at the minor axis' level (in the spirit of Mavridis & Papaioannou 2011).",
               "8 texels per probe, probes = ceil(major / minor) <= max_probes", _LINEAR,
               (Param("max_probes", 8, 1, 32, int, "most probes along the major axis"), _ALPHA),
               twin_tolerance=5e-3),  # hardware trilinear probes
        Filter("ewa_vis", "EWA that drops the footprint texels the relief hides (the full method of Romanyuk & "
               "Dudnyk 2017, filtering with parallax mapping): the view ray towards each texel's surface point is "
               "traced with the technique's own search; a texel whose ray meets the relief first gets no weight.",
               "EWA texels + one trace per texel", _LINEAR,
               (_MAX_TEXELS, _ALPHA, _INHERIT), texel_loop=True, visibility=True, twin_tolerance=1e-4),
        Filter("ewa_vis_rows", "EWA with that paper's cheap visibility: each row of the ellipse is walked from one end "
               "until a hidden texel, then from the other end back until a hidden texel; the texels between are "
               "dropped without being traced.", "EWA texels + one trace per texel walked", _LINEAR,
               (_MAX_TEXELS, _ALPHA, _INHERIT), texel_loop=True, visibility=True, twin_tolerance=1e-4),
    )
}

DERIVATIVE_SOURCES: dict[str, DerivativeSource] = {
    d.name: d
    for d in (
        DerivativeSource("uv", "screen-space derivatives of the unperturbed surface uv (before the ray search)",
                         traced=False),
        DerivativeSource("displaced", "screen-space differences of the traced hit uv (Romanyuk & Dudnyk 2017, formula 3), "
                         f"bounded to {DERIVATIVE_LIMIT:g}x the unperturbed length"),
        DerivativeSource("analytic", "the hit's local Jacobian from the relief slope g there: "
                         "(I - P g^T / (1 + g.P)) (duv - t dP), bounded the same way"),
    )
}


def get_filter(name: str, where: str = "filter") -> Filter:
    try:
        return FILTERS[name]
    except KeyError:
        raise UserError(f"{where} = {name!r}: unknown filter; expected one of {', '.join(FILTERS)}") from None


def get_derivatives(name: str, where: str = "derivatives") -> DerivativeSource:
    try:
        return DERIVATIVE_SOURCES[name]
    except KeyError:
        raise UserError(f"{where} = {name!r}: unknown derivative source; expected one of "
                        f"{', '.join(DERIVATIVE_SOURCES)}") from None


def resolve_filter_params(f: Filter, overrides: dict | None = None, where: str = "") -> dict:
    """Defaults merged with checked overrides (unknown names are errors naming ``where``)."""
    return resolve_params(f, overrides, where, "filter")


def filter_params(f: Filter) -> Struct:
    """The filter's FilterParams uniform: its parameters in order (counts u32, real numbers f32), padded to 16
    bytes."""
    return scalar_uniform("FilterParams", f.uniform_fields)


def filter_uniform_size(f: Filter) -> int:
    return filter_params(f).size


def filter_interface(f: Filter) -> Generated:
    """The WGSL a filter's module must agree on with Python: FilterParams, parameter caps, flags, constants."""
    lines = [f"// Generated from the registry entry of filter {f.name!r} (wgpuviewer/relief/filters.py).",
             filter_params(f).wgsl().rstrip("\n"),
             f"const VIS_TOLERANCE: f32 = {f32_literal(VIS_TOLERANCE)};",
             f"const DERIVATIVE_LIMIT: f32 = {f32_literal(DERIVATIVE_LIMIT)};"]
    lines += [f"const FLAG_{name.upper()}: u32 = {bit}u;" for name, bit in FLAGS.items()]
    lines += range_constants(f.params)
    lines += [f"@group({FILTER_GROUP}) @binding(0) var<uniform> filter_params: FilterParams;",
              f"@group({FILTER_GROUP}) @binding(1) var filter_sampler: sampler;"]
    return Generated(f"<generated: {f.name} filter interface>", "\n".join(lines) + "\n")


def pack_filter_params(f: Filter, params: dict) -> bytes:
    """FilterParams uniform data, each value in its field's type (missing values take the defaults)."""
    values = {**f.defaults(), **params}
    return filter_params(f).pack({p.name: values[p.name] for p in f.params})


def sampler_descriptor(f: Filter, params: dict) -> dict:
    """``device.create_sampler`` arguments of a filter (repeat addressing, as the material's textures tile)."""
    mag, minf, mip = f.sampler
    anisotropy = int(params.get("max_anisotropy", 1))
    return {"address_mode_u": "repeat", "address_mode_v": "repeat", "mag_filter": mag, "min_filter": minf,
            "mipmap_filter": mip, "max_anisotropy": anisotropy}


def markdown_table() -> str:
    """The README's filter table: name (the default marked), what it does, what it reads per lookup."""
    rows = ["| filter | what | reads per lookup |", "|---|---|---|"]
    for f in FILTERS.values():
        name = f"`{f.name}`" + (" (default)" if f.name == DEFAULT_FILTER else "")
        rows.append(f"| {name} | {f.description} | {f.cost} |")
    return "\n".join(rows)
