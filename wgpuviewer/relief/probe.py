"""Run a technique's WGSL ``trace`` on arbitrary rays in a compute shader.

The probe composes the same ``trace`` function the fragment shader uses (shaders.compose_technique), so
what it measures is what the renderer draws. Compare its hits with ``wgpuviewer.reference.exact_hit``.

Inputs are checked like ``exact_hit`` checks them (shapes naming the array, finite values, heights in [0, 1],
``height_scale`` finite and in [0, MAX_HEIGHT_SCALE]); misuse raises ``InputError`` (a ValueError). The GPU
traces in float32, which cannot hold a fraction of a texel far from the origin (at uv ~ 1e7 the spacing of
float32 is a whole texture): with repeat addressing the integer part of each entry uv is removed in float64
before tracing and added back to the hit (exact: repeat is periodic); with clamp addressing, rays entering
farther out than float32 resolves to 1/64 texel are flagged ``capped``. So is any ray whose hit is not finite.

``shadow_probe`` runs the renderer's self-shadowing (``common/shadow.wgsl``: the hard shadow through the technique's
``trace``, the soft estimate) on given points and lights; compare it with ``wgpuviewer.relief.reference.shadow``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import wgpu

from maptools import validate_height
from wgpuviewer.core.compute import Kernel, compute_for
from wgpuviewer.core.errors import InputError
from wgpuviewer.core.gpu import Gpu, get_gpu
from wgpuviewer.core.params import resolve_params
from wgpuviewer.core.structs import Struct
from wgpuviewer.techniques import TECHNIQUES, get_technique

from .maps import MAP_SLOTS, PARAMS_BINDING, SAMPLER_BINDING, binding, depth_range, layout_entries
from .reference import real_array, real_number
from .shaders import compose_technique, pack_trace_params

#: The probe's records (entry/probe.wgsl binds an array of each and declares neither): a ray in, its hit out.
#: view: V in tangent space; dx, dy: the ray's pixel footprint, uv per pixel along screen x and y (zero: none).
PROBE_RAY = Struct("ProbeRay", [("uv", "vec2f"), ("view", "vec3f"), ("dx", "vec2f"), ("dy", "vec2f")], "storage")
PROBE_HIT = Struct("ProbeHit", [("uv", "vec2f"), ("depth", "f32"), ("fetches", "u32"), ("capped", "u32"),
                                ("layers", "u32")], "storage")
#: The shadow probe's records (entry/shadow_probe.wgsl): a point in the relief and a light in, its shadows out.
SHADOW_POINT = Struct("ShadowPoint", [("uv", "vec2f"), ("depth", "f32"), ("light", "vec3f")], "storage")
SHADOW_OUT = Struct("ShadowOut", [("hard", "f32"), ("soft", "f32"), ("hard_fetches", "u32"),
                                  ("soft_fetches", "u32"), ("capped", "u32")], "storage")
SHADOW_ENTRY = "shadow_main"
WORKGROUP = 64  # @workgroup_size of the probe entry points
_MAX_GROUPS = 65535  # workgroups along x of a large set (common/probe_index.wgsl folds the 2D grid at this width)
ENTRY = "probe_main"
#: What a user can do when the probe kernel does not build on their adapter, or the rays do not fit its limits.
FIX = "fix the WGSL at that line, or run on another adapter (backend=...)"
FEWER = "trace fewer rays per call"
#: Largest relief depth the probe traces (UV units): beyond it float32 steps overflow; scenes allow up to 1.
MAX_HEIGHT_SCALE = 1e3
#: Clamp addressing: entry uv farther out than this many texels of float32 resolution (2^-6 texel) is flagged.
_CLAMP_RESOLVED = 2.0 ** (23 - 6)


@dataclass
class ProbeResult:
    uv: np.ndarray  # (N, 2) float64 hit uv, not wrapped (the entry's integer part added back in float64)
    depth: np.ndarray  # (N,) float32 hit layer depth t
    fetches: np.ndarray  # (N,) uint32 depth fetches per ray
    capped: np.ndarray  # (N,) bool: a cap or clamp decided the result
    layers: np.ndarray  # (N,) uint32 depth layers the search used (0: technique without layers)


def _derived(technique) -> list[str]:
    """The height-derived slots a technique samples: all the probe binds (it shades nothing)."""
    return [n for n in technique.textures if MAP_SLOTS[n].derived]


def material_layout_entries(technique, textures: tuple[str, ...] = ()) -> list[dict]:
    """Group 1 of a probe: the technique's uniform, the sampler, its derived maps and ``textures`` slots."""
    C = wgpu.ShaderStage.COMPUTE
    return [
        {"binding": PARAMS_BINDING, "visibility": C, "buffer": {"type": wgpu.BufferBindingType.uniform}},
        {"binding": SAMPLER_BINDING, "visibility": C, "sampler": {"type": wgpu.SamplerBindingType.filtering}},
        *layout_entries([*textures, *_derived(technique)], C),
    ]


def _kernel(gpu: Gpu, technique_name: str) -> Kernel:
    technique = get_technique(technique_name)
    C = wgpu.ShaderStage.COMPUTE
    compute = compute_for(gpu)
    layout = compute.layout([io_layout_entries(C), material_layout_entries(technique)], "probe")
    module = compose_technique(technique, "probe", records=(PROBE_RAY.generated(), PROBE_HIT.generated()))
    return compute.kernel_of(module, label=f"probe:{technique.name}", fix=FIX, layout=layout)


@dataclass
class ShadowProbeResult:
    lit: np.ndarray  # (N,) bool: the hard shadow state (True: the light reaches the point)
    visibility: np.ndarray  # (N,) float32 the soft estimate in [0, 1]
    hard_fetches: np.ndarray  # (N,) uint32 depth fetches of the hard shadow's trace
    soft_fetches: np.ndarray  # (N,) uint32 depth fetches of the soft estimate
    capped: np.ndarray  # (N,) bool: a cap or clamp decided it (grazing light, a capped trace)


def _shadow_kernel(gpu: Gpu, technique_name: str) -> Kernel:
    technique = get_technique(technique_name)
    C = wgpu.ShaderStage.COMPUTE
    compute = compute_for(gpu)
    layout = compute.layout([io_layout_entries(C), material_layout_entries(technique)], "shadow_probe")
    module = compose_technique(technique, "shadow_probe",
                               records=(SHADOW_POINT.generated(), SHADOW_OUT.generated()))
    return compute.kernel_of(module, label=f"shadow_probe:{technique.name}", fix=FIX, layout=layout)


def shadow_probe(technique: str, height: np.ndarray, uv, depth, light_dir, height_scale: float = 0.05, *,
                 backend: str | None = None, **params) -> ShadowProbeResult:
    """The renderer's hard and soft self-shadowing of N points with ``technique`` on the GPU (repeat addressing).

    height: (H, W) height map in [0, 1]; uv: (N, 2) points' uv in [0, 1) (the renderer traces the uv's fraction);
    depth: (N,) their layer depths t; light_dir: (N, 3) or (3,) tangent-space directions towards the light.
    params: technique parameters, validated against the registry.
    """
    tech = get_technique(technique)
    if not (tech.ray_search and tech.needs_depth):
        names = ", ".join(name for name, t in TECHNIQUES.items() if t.ray_search and t.needs_depth)
        raise InputError(f"shadow_probe: technique {technique!r} does not trace the relief; those that do: {names}")
    values = resolve_params(tech, params)
    height = validate_height(height, "shadow_probe: height", dtype=np.float64, error=InputError)
    scale = _check_height_scale(height_scale)
    uv = _rows(uv, 2, "uv")
    light = _rows(light_dir, 3, "light_dir")
    t = _rows(np.reshape(real_array(depth, "shadow_probe: depth"), (-1, 1)), 1, "depth")[:, 0]
    n = max(len(uv), len(light), len(t))
    try:
        uv, light, t = np.broadcast_to(uv, (n, 2)), np.broadcast_to(light, (n, 3)), np.broadcast_to(t, (n,))
    except ValueError:
        raise InputError(f"shadow_probe: uv has {len(uv)} rows, depth {len(t)} and light_dir {len(light)}; "
                         "expected equal counts, or one for all") from None
    if n == 0:
        return ShadowProbeResult(np.zeros(0, bool), np.zeros(0, np.float32), np.zeros(0, np.uint32),
                                 np.zeros(0, np.uint32), np.zeros(0, bool))
    gpu = get_gpu(backend, quiet=True)
    compute = compute_for(gpu)
    kernel = _shadow_kernel(gpu, tech.name)
    points = np.zeros(n, SHADOW_POINT.dtype)
    points["uv"], points["depth"], points["light"] = uv, t, light
    point_buf = compute.storage(SHADOW_POINT.pack_many(points), f"shadow_probe:{n} points", FEWER)
    out_buf = compute.storage(n * SHADOW_OUT.size, f"shadow_probe:shadows of {n} points", FEWER)
    layout = kernel.pipeline(SHADOW_ENTRY).get_bind_group_layout(1)
    group = material_bind_group(gpu, layout, tech, height, scale, values, "repeat")
    out = dispatch(kernel, SHADOW_ENTRY, [group], n, point_buf, out_buf, SHADOW_OUT)
    return ShadowProbeResult(lit=out["hard"] > 0.5, visibility=out["soft"].copy(),
                             hard_fetches=out["hard_fetches"].copy(), soft_fetches=out["soft_fetches"].copy(),
                             capped=out["capped"] != 0)


def probe(
    technique: str,
    height: np.ndarray,
    uv,
    view_dir,
    height_scale: float = 0.05,
    *,
    address: str = "repeat",
    backend: str | None = None,
    footprint=None,
    **params,
) -> ProbeResult:
    """Trace rays with ``technique`` on the GPU.

    height: (H, W) height map in [0, 1] (1 = top; the GPU gets depth = 1 - height). The maps the
    technique needs are built from it (cached by maptools), exactly as the renderer builds them.
    uv: (N, 2) or (2,) entry points; view_dir: (N, 3) or (3,) tangent-space V (towards the eye); one of them
    broadcasts against the other, and N = 0 gives an empty result. height_scale: relief depth in UV units.
    footprint: (N, 4) or (4,) each ray's pixel on screen, uv per pixel (du/dx, dv/dx, du/dy, dv/dy), as the renderer
    passes a fragment's derivatives (auto's ``max_error_px`` reads it); None: no footprint (zero).
    params: technique parameters (e.g. ``layers=64``), validated against the registry.
    """
    tech = get_technique(technique)
    if not tech.ray_search:
        names = ", ".join(name for name, t in TECHNIQUES.items() if t.ray_search)
        raise InputError(f"probe: technique {technique!r} does not trace rays; ray-search techniques: {names}")
    values = resolve_params(tech, params)
    height = validate_height(height, "probe: height", dtype=np.float64, error=InputError)
    if address not in ("repeat", "clamp"):
        raise InputError(f"probe: address = {address!r}; expected 'repeat' or 'clamp'")
    scale = _check_height_scale(height_scale)
    uv = _rows(uv, 2, "uv")
    view = _rows(view_dir, 3, "view_dir")
    if len(uv) != len(view) and 1 not in (len(uv), len(view)):
        raise InputError(f"probe: uv has {len(uv)} rows but view_dir has {len(view)}; expected equal counts, or "
                         "one row for all")
    n = max(len(uv), len(view)) if len(uv) and len(view) else 0
    pixel = np.zeros((1, 4)) if footprint is None else _rows(footprint, 4, "footprint")
    if len(pixel) not in (1, n):
        raise InputError(f"probe: footprint has {len(pixel)} rows for {n} rays; expected one per ray, or one row for all")
    uv = np.broadcast_to(uv, (n, 2))
    view = np.broadcast_to(view, (n, 3))
    if n == 0:
        return ProbeResult(uv=np.zeros((0, 2)), depth=np.zeros(0, np.float32), fetches=np.zeros(0, np.uint32),
                           capped=np.zeros(0, bool), layers=np.zeros(0, np.uint32))
    if address == "repeat":  # periodic: trace the fraction, add the integer part back in float64
        offset = np.floor(uv)
        far = np.zeros(n, bool)
    else:
        offset = np.zeros_like(uv)
        far = (np.abs(uv) > _CLAMP_RESOLVED / max(height.shape)).any(axis=1)
    hits = _trace(tech, values, height, uv - offset, view, np.broadcast_to(pixel, (n, 4)), scale, address, backend)
    hits.uv = hits.uv + offset
    hits.capped |= far | ~np.isfinite(hits.uv).all(axis=1) | ~np.isfinite(hits.depth)
    return hits


def _check_height_scale(height_scale) -> float:
    scale = real_number(height_scale, "probe: height_scale")
    if not (np.isfinite(scale) and 0.0 <= scale <= MAX_HEIGHT_SCALE):
        raise InputError(f"probe: height_scale = {height_scale!r}; expected a finite relief depth from 0 to "
                         f"{MAX_HEIGHT_SCALE:g} UV units")
    return scale


def _rows(a, width: int, name: str) -> np.ndarray:
    """(width,) or (N, width) finite values -> float64 (N, width); the error names the array."""
    arr = real_array(a, f"probe: {name}")
    if arr.ndim == 1 and arr.shape[0] == width:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != width:
        raise InputError(f"probe: {name} must have shape ({width},) or (N, {width}), got {np.shape(a)}")
    if not np.isfinite(arr).all():
        raise InputError(f"probe: {name} contains NaN/inf; expected finite values")
    return arr


def _trace(tech, values: dict, height: np.ndarray, uv: np.ndarray, view: np.ndarray, pixel: np.ndarray,
           height_scale: float, address: str, backend) -> ProbeResult:
    """Run the technique's probe kernel on the rays (uv, view, pixel: float64 (n, 2), (n, 3), (n, 4), n >= 1)."""
    n = len(uv)
    gpu = get_gpu(backend, quiet=True)
    compute = compute_for(gpu)
    kernel = _kernel(gpu, tech.name)
    rays = np.zeros(n, PROBE_RAY.dtype)
    rays["uv"], rays["view"], rays["dx"], rays["dy"] = uv, view, pixel[:, :2], pixel[:, 2:]
    ray_buf = compute.storage(PROBE_RAY.pack_many(rays), f"probe:{n} rays", FEWER)
    hit_buf = compute.storage(n * PROBE_HIT.size, f"probe:hits of {n} rays", FEWER)
    layout = kernel.pipeline(ENTRY).get_bind_group_layout(1)
    material_group = material_bind_group(gpu, layout, tech, height, height_scale, values, address)
    hits = dispatch(kernel, ENTRY, [material_group], n, ray_buf, hit_buf, PROBE_HIT)
    return ProbeResult(uv=hits["uv"].astype(np.float64), depth=hits["depth"].copy(), fetches=hits["fetches"].copy(),
                       capped=hits["capped"] != 0, layers=hits["layers"].copy())


def io_layout_entries(visibility) -> list[dict]:
    """Group 0 of a probe: its inputs (read-only storage) and outputs (storage)."""
    return [
        {"binding": 0, "visibility": visibility, "buffer": {"type": wgpu.BufferBindingType.read_only_storage}},
        {"binding": 1, "visibility": visibility, "buffer": {"type": wgpu.BufferBindingType.storage}},
    ]


def material_bind_group(gpu: Gpu, layout, tech, height: np.ndarray, height_scale: float, values: dict,
                        address: str, extra: tuple = ()) -> wgpu.GPUBindGroup:
    """Group 1 of a probe: the technique's uniform, a linear sampler with ``address``, its height-derived maps
    built from ``height`` as the renderer builds them, and ``extra`` (binding, texture) pairs."""
    device = gpu.device
    params_buf = device.create_buffer_with_data(
        label="probe:params", data=pack_trace_params(tech, height_scale, height.shape, values,
                                                     depth_range(1.0 - height, gpu.depth_format)),
        usage=wgpu.BufferUsage.UNIFORM,
    )
    depth = 1.0 - height
    maps = [(binding(n), MAP_SLOTS[n].build(gpu, depth, height_scale, f"probe:{n}"))
            for n in _derived(tech)]
    mode = wgpu.AddressMode.repeat if address == "repeat" else wgpu.AddressMode.clamp_to_edge
    sampler = device.create_sampler(
        label="probe:sampler", address_mode_u=mode, address_mode_v=mode, mag_filter="linear", min_filter="linear"
    )
    return compute_for(gpu).bind_group(layout, {PARAMS_BINDING: params_buf, SAMPLER_BINDING: sampler,
                                                 **{b: texture.create_view() for b, texture in [*maps, *extra]}},
                                        "probe:material")


def dispatch(kernel: Kernel, entry: str, groups: list, n: int, inputs: wgpu.GPUBuffer, outputs: wgpu.GPUBuffer,
             output: Struct) -> np.ndarray:
    """Run a probe kernel over ``n`` items: group 0 binds ``inputs`` and ``outputs``, then ``groups`` (index - 1 =
    group; None: skip); read ``outputs`` back as ``n`` records of ``output`` (a structured array of its dtype)."""
    compute = kernel.compute
    count = -(-n // WORKGROUP)
    encoder = compute.encoder("probe")
    # Large sets: a 2D grid of workgroups; the shader folds it back into one index (common/probe_index.wgsl).
    threads = (WORKGROUP * min(count, _MAX_GROUPS), -(-count // _MAX_GROUPS))
    kernel.dispatch(encoder, entry, {0: inputs, 1: outputs}, threads, size=(WORKGROUP,), groups=groups)
    compute.submit(encoder)
    return output.unpack(compute.read(outputs, n * output.size, np.uint8), n)
