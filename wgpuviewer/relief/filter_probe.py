"""Run a texture filter's WGSL ``filter_texture`` on arbitrary footprints in a compute shader.

The probe composes the same filter (and, for the visibility filters, the same technique ``trace``) the fragment
shader uses (``shaders.compose_technique(..., "filter_probe", filter)``), over a texture uploaded as the renderer
uploads albedo (rgba16float, box-filtered mip chain). Tests compare it with the float64 filters of
``wgpuviewer.studies.filtering.cpu`` on the same footprints, including ones no render produces (zero, NaN and
huge derivatives).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import wgpu

from wgpuviewer.core.compute import Kernel, compute_for
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import Gpu, create_texture, get_gpu, mip_chain
from wgpuviewer.core.structs import Struct

from .filters import FILTER_GROUP, get_filter, pack_filter_params, resolve_filter_params, sampler_descriptor
from .maps import binding
from .probe import FEWER, FIX, dispatch, io_layout_entries, material_bind_group, material_layout_entries
from .shaders import compose_technique
from .techniques import get_technique, resolve_params

#: The filter probe's records (entry/filter_probe.wgsl binds an array of each and declares neither): a footprint
#: in (view: V in tangent space, for visibility traces); the filtered value and the filter's statistics out.
FILTER_SAMPLE = Struct("FilterSample", [("uv", "vec2f"), ("dx", "vec2f"), ("dy", "vec2f"), ("view", "vec3f")],
                       "storage")
FILTER_OUT = Struct("FilterOut", [("value", "vec4f"), ("texels", "u32"), ("depth_fetches", "u32"),
                                  ("hidden", "u32"), ("flags", "u32")], "storage")
TEXTURE_FORMAT = "rgba16float"  # as the renderer's albedo
ENTRY = "filter_probe_main"


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
