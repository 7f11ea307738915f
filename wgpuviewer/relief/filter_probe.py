"""Run a texture filter's WGSL ``filter_texture`` on arbitrary footprints in a compute shader.

The probe composes the same filter (and, for the visibility filters, the same technique ``trace``) the fragment
shader uses (``shaders.compose_technique(..., "filter_probe", filter)``), over a texture uploaded as the renderer
uploads albedo (rgba16float, box-filtered mip chain). Tests compare it with the float64 filters of
``wgpuviewer.lab.studies.filtering.cpu`` on the same footprints, including ones no render produces (zero, NaN and
huge derivatives).

``explicit_gradient_support(gpu)`` asks the adapter whether it honours ``textureSampleGrad``'s explicit gradients
(a small compute probe, run once per device): software adapters (lavapipe) ignore them with an anisotropic
sampler, so the hardware ``aniso`` filter cannot be measured there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import wgpu

from wgpuviewer.core.compute import Kernel, compute_for
from wgpuviewer.core.errors import InputError, UserError
from wgpuviewer.core.gpu import Gpu, create_texture, get_gpu, mip_chain
from wgpuviewer.core.params import resolve_params
from wgpuviewer.core.structs import Struct
from wgpuviewer.techniques import get_technique

from .filters import FILTER_GROUP, get_filter, pack_filter_params, resolve_filter_params, sampler_descriptor
from .maps import binding
from .probe import FEWER, FIX, dispatch, io_layout_entries, material_bind_group, material_layout_entries
from .shaders import compose_technique

#: The filter probe's records (entry/filter_probe.wgsl binds an array of each and declares neither): a footprint
#: in (view: V in tangent space, for visibility traces); the filtered value and the filter's statistics out.
FILTER_SAMPLE = Struct("FilterSample", [("uv", "vec2f"), ("dx", "vec2f"), ("dy", "vec2f"), ("view", "vec3f")],
                       "storage")
FILTER_OUT = Struct("FilterOut", [("value", "vec4f"), ("texels", "u32"), ("depth_fetches", "u32"),
                                  ("hidden", "u32"), ("flags", "u32")], "storage")
TEXTURE_FORMAT = "rgba16float"  # as the renderer's albedo
ENTRY = "filter_probe_main"

#: The explicit-gradient probe's records (entry/gradient_probe.wgsl binds an array of each and declares neither):
#: a uv and gradient pair in; the red channel read through the isotropic and the anisotropic sampler out.
GRADIENT_SAMPLE = Struct("GradientSample", [("uv", "vec2f"), ("ddx", "vec2f"), ("ddy", "vec2f")], "storage")
GRADIENT_VALUE = Struct("GradientValue", [("isotropic", "f32"), ("anisotropic", "f32")], "storage")
GRADIENT_ENTRY = "gradient_probe_main"
#: The probe texture's side: level 0 horizontal 1-texel stripes (row j is j % 2), so every coarser level is 0.5.
GRADIENT_TEXTURE = 64
#: Where it is read: the centre of texel (32, 33), on a stripe of value 1 (level 0 reads 1, any coarser level 0.5).
GRADIENT_TEXEL = (32, 33)
#: The probe's gradient pairs (ddx, ddy) in texels: which level each must read when the gradients are honoured.
GRADIENT_PAIRS = {
    "tiny": ((0.25, 0.0), (0.0, 0.25)),  # magnified: level 0, 1
    "huge": ((64.0, 0.0), (0.0, 64.0)),  # the 1x1 level: 0.5
    "thin": ((16.0, 0.0), (0.0, 1.0)),  # 16:1 along the stripes: level 0 with max_anisotropy 16, 1; level 4 without
    "round": ((16.0, 0.0), (0.0, 16.0)),  # level 4 for any sampler: 0.5
}
#: The anisotropic sampler's max_anisotropy (WebGPU's largest, the study's `aniso 16`).
GRADIENT_ANISOTROPY = 16
#: Smallest difference between two of the probe's reads that shows a level change (level 0 vs coarser: 0.5).
GRADIENT_CONTRAST = 0.25
#: The probe's kinds of sampler: isotropic trilinear, and anisotropic with GRADIENT_ANISOTROPY.
SAMPLER_KINDS = ("isotropic", "anisotropic")
#: Its checks: (sampler kind, the pair that must read level 0, the pair that must read a coarser level, what the
#: adapter ignores when it does not).
_GRADIENT_CHECKS = (
    ("isotropic", "tiny", "huge", "length with an isotropic sampler"),
    ("anisotropic", "tiny", "huge", f"length with an anisotropic sampler (max_anisotropy {GRADIENT_ANISOTROPY})"),
    ("anisotropic", "thin", "round", "shape: through the anisotropic sampler a 16:1 pair reads a round pair's level"),
)


@dataclass
class FilterProbeResult:
    value: np.ndarray  # (N, 4) float32 filtered texel value
    texels: np.ndarray  # (N,) uint32 texels read (hardware samples counted as the texels they blend)
    depth_fetches: np.ndarray  # (N,) uint32 depth fetches of visibility traces
    hidden: np.ndarray  # (N,) uint32 texels dropped as hidden
    flags: np.ndarray  # (N,) uint32 filters.FLAGS bits


def _kernel(gpu: Gpu, technique_name: str, filter_name: str) -> Kernel:
    technique = get_technique(technique_name)
    C = wgpu.ShaderStage.COMPUTE
    groups = [io_layout_entries(C), material_layout_entries(technique, ("albedo",))]
    groups += [[]] * (FILTER_GROUP - 2)
    groups.append([{"binding": 0, "visibility": C, "buffer": {"type": wgpu.BufferBindingType.uniform}},
                   {"binding": 1, "visibility": C, "sampler": {"type": wgpu.SamplerBindingType.filtering}}])
    compute = compute_for(gpu)
    module = compose_technique(technique, "filter_probe", filter_name,
                               records=(FILTER_SAMPLE.generated(), FILTER_OUT.generated()))
    return compute.kernel_of(module, label=f"filter-probe:{technique_name}/{filter_name}", fix=FIX,
                             layout=compute.layout(groups, "filter-probe"))


def texture_levels(texture: np.ndarray) -> list[np.ndarray]:
    """The mip chain the probe uploads, as float64 arrays of the values the GPU holds (float16-rounded RGBA)."""
    data = np.asarray(texture, np.float32)
    if data.ndim == 2:
        data = data[:, :, None]
    if data.shape[2] < 4:
        pad = np.ones(data.shape[:2] + (4 - data.shape[2],), np.float32)
        data = np.concatenate([data, pad], axis=2)
    return [np.asarray(level, np.float16).astype(np.float64) for level in mip_chain(data[:, :, :4])]


def filter_probe(
    filter: str,
    texture: np.ndarray,
    uv,
    dx,
    dy,
    view_dir=(0.0, 0.0, 1.0),
    *,
    height: np.ndarray | None = None,
    height_scale: float = 0.05,
    technique: str = "maxmip",
    filter_params: dict | None = None,
    technique_params: dict | None = None,
    backend: str | None = None,
) -> FilterProbeResult:
    """Filter ``texture`` (H, W, C) at N footprints on the GPU.

    uv, dx, dy: (N, 2) the hit uv and its screen-space derivatives (UV units per pixel); view_dir: (N, 3) or
    (3,) tangent-space V. With ``height`` (a height map in [0, 1], 1 = top) the module traces with
    ``technique`` (default the exact ``maxmip``) and the visibility filters drop hidden texels; without it the
    surface is flat (technique ``basic``).
    """
    f = get_filter(filter)
    values = resolve_filter_params(f, filter_params)
    tech = get_technique(technique if height is not None else "basic")
    tech_values = resolve_params(tech, technique_params)
    if height is None:
        height = np.ones((1, 1))
    height = np.asarray(height, np.float64)
    if height.ndim != 2 or height.size == 0 or not np.isfinite(height).all():
        raise UserError("filter probe: height must be a non-empty finite 2D array")
    columns = [np.atleast_2d(np.asarray(a, np.float32)) for a in (uv, dx, dy, view_dir)]
    n = max(len(c) for c in columns)
    uv, dx, dy, view = (np.broadcast_to(c, (n, c.shape[1])) for c in columns)

    gpu = get_gpu(backend, quiet=True)
    compute = compute_for(gpu)
    kernel = _kernel(gpu, tech.name, f.name)
    pipeline = kernel.pipeline(ENTRY)
    samples = np.zeros(n, FILTER_SAMPLE.dtype)
    samples["uv"], samples["dx"], samples["dy"], samples["view"] = uv, dx, dy, view
    in_buf = compute.storage(FILTER_SAMPLE.pack_many(samples), f"filter-probe:{n} samples", FEWER)
    out_buf = compute.storage(n * FILTER_OUT.size, f"filter-probe:out of {n} samples", FEWER)
    albedo = create_texture(gpu, mip_chain(np.asarray(texture, np.float32)), TEXTURE_FORMAT, "filter-probe:texture")
    material = material_bind_group(gpu, pipeline.get_bind_group_layout(1), tech, height, height_scale, tech_values,
                                   "repeat", extra=((binding("albedo"), albedo),))
    params = compute.uniform(pack_filter_params(f, values), "filter-probe:params")
    sampler = gpu.device.create_sampler(label=f"filter-probe:{f.name}", **sampler_descriptor(f, values))
    filter_group = compute.bind_group(pipeline.get_bind_group_layout(FILTER_GROUP), {0: params, 1: sampler},
                                      f"filter-probe:{f.name}")
    groups = [material, *[None] * (FILTER_GROUP - 2), filter_group]
    out = dispatch(kernel, ENTRY, groups, n, in_buf, out_buf, FILTER_OUT)
    return FilterProbeResult(**{name: out[name].copy() for name in FILTER_OUT.names})  # FilterOut's fields, by name


@dataclass(frozen=True)
class GradientProbe:
    """What the explicit-gradient probe read (GRADIENT_PAIRS name -> red value) through each sampler."""

    adapter: str
    isotropic: dict[str, float]
    anisotropic: dict[str, float]

    def ignored_by(self, sampler: str | None = None) -> list[str]:
        """What the adapter ignores through ``sampler`` (a SAMPLER_KINDS entry; None: either), as phrases."""
        return ignored_gradients(self.isotropic, self.anisotropic, sampler)

    @property
    def ignored(self) -> list[str]:
        return self.ignored_by()

    def honoured_by(self, sampler: str | None = None) -> bool:
        return not self.ignored_by(sampler)

    @property
    def honoured(self) -> bool:
        return self.honoured_by()


def ignored_gradients(isotropic: dict[str, float], anisotropic: dict[str, float],
                      sampler: str | None = None) -> list[str]:
    """The decision of the explicit-gradient probe, from its reads (GRADIENT_PAIRS name -> value): what the
    adapter ignores through ``sampler`` (a SAMPLER_KINDS entry; None: either), as phrases for a sentence ([] when
    it honours the gradients). Honoured gradients read level 0 (1) at the tiny pair and a coarse level (0.5) at the
    huge one through both samplers, and level 0 at the 16:1 thin pair through the anisotropic sampler where the
    round pair of the same major axis reads level 4."""
    if sampler is not None and sampler not in SAMPLER_KINDS:
        raise InputError(f"sampler = {sampler!r}: expected one of {', '.join(SAMPLER_KINDS)} or None")
    reads = {"isotropic": isotropic, "anisotropic": anisotropic}
    ignored = []
    for kind, fine, coarse, phrase in _GRADIENT_CHECKS:
        difference = reads[kind][fine] - reads[kind][coarse]
        if sampler in (None, kind) and not (np.isfinite(difference) and difference > GRADIENT_CONTRAST):
            ignored.append(phrase)
    return ignored


def gradient_probe_texture() -> np.ndarray:
    """The probe texture's level 0 (RGBA): horizontal 1-texel stripes, row j = j % 2."""
    rows = np.arange(GRADIENT_TEXTURE) % 2
    return np.broadcast_to(rows[:, None, None], (GRADIENT_TEXTURE, GRADIENT_TEXTURE, 4)).astype(np.float32)


def explicit_gradient_probe(gpu: Gpu) -> GradientProbe:
    """Run the explicit-gradient probe on ``gpu`` (once per device: the result is kept in ``gpu.cache``)."""
    with gpu.lock:
        if "explicit-gradients" not in gpu.cache:
            gpu.cache["explicit-gradients"] = _run_gradient_probe(gpu)
        return gpu.cache["explicit-gradients"]


def _run_gradient_probe(gpu: Gpu) -> GradientProbe:
    compute = compute_for(gpu)
    module_parts = (GRADIENT_SAMPLE.generated(), GRADIENT_VALUE.generated(), "entry/gradient_probe.wgsl")
    kernel = compute.kernel(*module_parts, label="gradient-probe", fix=FIX)
    names = list(GRADIENT_PAIRS)
    samples = np.zeros(len(names), GRADIENT_SAMPLE.dtype)
    samples["uv"] = (np.array(GRADIENT_TEXEL) + 0.5) / GRADIENT_TEXTURE
    samples["ddx"] = [np.array(GRADIENT_PAIRS[n][0]) / GRADIENT_TEXTURE for n in names]
    samples["ddy"] = [np.array(GRADIENT_PAIRS[n][1]) / GRADIENT_TEXTURE for n in names]
    with compute.guard("explicit-gradient probe", FIX):
        texture = create_texture(gpu, mip_chain(gradient_probe_texture()), TEXTURE_FORMAT, "gradient-probe:stripes")
        linear = {"mag_filter": "linear", "min_filter": "linear", "mipmap_filter": "linear"}
        isotropic = gpu.device.create_sampler(label="gradient-probe:isotropic", **linear)
        anisotropic = gpu.device.create_sampler(label="gradient-probe:anisotropic", max_anisotropy=GRADIENT_ANISOTROPY,
                                                **linear)
        group = kernel.bind(GRADIENT_ENTRY, {0: texture.create_view(), 1: isotropic, 2: anisotropic}, group=1)
        in_buf = compute.storage(GRADIENT_SAMPLE.pack_many(samples), "gradient-probe:samples", FIX)
        out_buf = compute.storage(len(names) * GRADIENT_VALUE.size, "gradient-probe:values", FIX)
        out = dispatch(kernel, GRADIENT_ENTRY, [group], len(names), in_buf, out_buf, GRADIENT_VALUE)
    return GradientProbe(gpu.summary, {n: float(v) for n, v in zip(names, out["isotropic"])},
                         {n: float(v) for n, v in zip(names, out["anisotropic"])})


def explicit_gradient_support(gpu: Gpu, sampler: str | None = None) -> bool:
    """Whether ``gpu`` honours ``textureSampleGrad``'s explicit gradients through ``sampler`` (a SAMPLER_KINDS
    entry; None: both kinds). Where it does not, a filter sampling through that kind (the ``aniso`` filter: the
    anisotropic one) is given the driver's footprint, not the derivative source's, and its numbers are the
    driver's."""
    return explicit_gradient_probe(gpu).honoured_by(sampler)


def explicit_gradient_note(gpu: Gpu, sampler: str | None = None) -> str:
    """One sentence for reports when ``gpu`` ignores explicit gradients through ``sampler`` (None: either kind);
    "" when it honours them."""
    probe = explicit_gradient_probe(gpu)
    ignored = probe.ignored_by(sampler)
    if not ignored:
        return ""
    kinds = [kind for kind in SAMPLER_KINDS if sampler in (None, kind) and not probe.honoured_by(kind)]
    return (f"{gpu.summary} ignores textureSampleGrad's explicit gradients ({'; '.join(ignored)}): a filter "
            f"sampling through {' or '.join(f'an {k}' for k in kinds)} sampler there is not measured validly.")
