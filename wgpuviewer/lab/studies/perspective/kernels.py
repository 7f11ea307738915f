"""The methods as WGSL compute kernels (``wgsl/studies/perspective/kernels.wgsl``), run on spans and timed.

One shader module holds every kernel; they share one bind group layout (the Params uniform, the spans, the per-span
constants, the uv and flag outputs). The records Python and WGSL share, ``PARAMS`` and ``SPAN``, are
``core.structs.Struct``s generated into the module and packed by field name. ``Kernels.prepare`` uploads one
method's inputs and returns a ``Dispatch`` that records the method's pass (for timing) and reads its output back as
a ``methods.Result``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import wgpu

from wgpuviewer.core.compute import compute_for, workgroups
from wgpuviewer.core.gpu import Gpu
from wgpuviewer.core.structs import Struct
from wgpuviewer.core.wgsl import Generated

from .geometry import Spans, defined_range
from .methods import METHODS, Method, Result, fixed_setup, split

SOURCE = "studies/perspective/kernels.wgsl"
#: Kernels that are forms of a shared entry point (one thread per pixel, or one per span walking it), with the
#: value of its pipeline-overridable FORM (generated into the module as FORM_* constants).
FORMS = {"direct": ("per_pixel", 0), "span": ("per_pixel", 1), "direct_rcp": ("per_pixel", 2),
         "span_rcp": ("per_pixel", 3), "incremental": ("sequential", 4), "reanchor": ("sequential", 5),
         "kahan": ("sequential", 6), "double_single": ("sequential", 7), "fixed16_16": ("sequential", 8)}
#: Kernels that read the per-span constants ``span_setup`` writes.
AFTER_SPAN_SETUP = ("span", "span_rcp")
WORKGROUP = 64  # @workgroup_size of every kernel
#: What a user can do when a kernel does not build on their adapter, or the spans do not fit its limits.
FIX = "run on another adapter (--backend)"
FEWER = "use fewer spans"
#: The uniform P (``common.wgsl``): the polygon's coefficients as columns over the quantities (w_u, w_v, q), what
#: the fixed-point and double-single forms add, the spans' size and the method's parameter.
PARAMS = Struct("Params", [
    ("a", "vec3f"), ("b", "vec3f"), ("c", "vec3f"),  # A1, A2, D / B1, B2, E / C1, C2, F: the x, y and constant terms
    ("a_lo", "vec3f"),  # double_single: the float64 x coefficients minus a (their f32 parts)
    ("fixed_step", "vec3i"),  # fixed16_16: the x coefficients in 16.16 units of each quantity's scale
    ("fixed_ratio", "vec2f"),  # fixed16_16: scale(q) / scale(w_u), scale(q) / scale(w_v) (powers of two)
    ("span_length", "u32"), ("span_count", "u32"),
    ("param", "u32"),  # k (parallel), S (subdivided) or M (reanchor)
    ("one", "f32")])  # 1.0 from the host: a factor the compiler cannot fold (arith.Arith.guard)
#: One span of the read-only ``spans`` array.
SPAN = Struct("Span", [
    ("x0", "i32"), ("y", "i32"),
    ("defined", "vec2i"),  # the span setup's clip (geometry.defined_range): pixels n in [x, y) are computed
    ("fixed_start", "vec3i")], "storage")  # fixed16_16: w_u, w_v, q at n = 0 in 16.16 units


def pack_params(method: Method, coefficients: np.ndarray, spans: Spans) -> bytes:
    k64 = np.asarray(coefficients, np.float64)
    k = k64.astype(np.float32)
    fixed_step, fixed_ratio = np.zeros(3, np.int32), np.zeros(2, np.float32)
    if method.kernel == "fixed16_16":
        fx = fixed_setup(k64, spans)
        fixed_step, fixed_ratio = fx.steps, fx.ratio
    return PARAMS.pack({"a": k[:, 0], "b": k[:, 1], "c": k[:, 2], "a_lo": split(k64)[1][:, 0],
                        "fixed_step": fixed_step, "fixed_ratio": fixed_ratio, "span_length": spans.length,
                        "span_count": spans.count, "param": method.param, "one": 1.0})


def pack_spans(method: Method, coefficients: np.ndarray, spans: Spans) -> bytes:
    records = np.zeros(spans.count, SPAN.dtype)
    records["x0"], records["y"] = spans.x0, spans.y
    records["defined"] = np.stack(defined_range(coefficients, spans), axis=1)
    if method.kernel == "fixed16_16":
        records["fixed_start"] = fixed_setup(coefficients, spans).starts.T
    return SPAN.pack_many(records)


def kernels_for(gpu: Gpu) -> Kernels:
    """The device's compiled kernels (built once per device)."""
    if "perspective_kernels" not in gpu.cache:
        gpu.cache["perspective_kernels"] = Kernels(gpu)
    return gpu.cache["perspective_kernels"]


class Kernels:
    """The study's shader module (a ``core.compute`` kernel with the shared layout) and its buffers, on one device."""

    def __init__(self, gpu: Gpu):
        self.gpu = gpu
        self.compute = compute_for(gpu)
        device = gpu.device
        C = wgpu.ShaderStage.COMPUTE
        storage = wgpu.BufferBindingType.storage
        self.layout = device.create_bind_group_layout(label="perspective", entries=[
            {"binding": 0, "visibility": C, "buffer": {"type": wgpu.BufferBindingType.uniform}},
            {"binding": 1, "visibility": C, "buffer": {"type": wgpu.BufferBindingType.read_only_storage}},
            *({"binding": b, "visibility": C, "buffer": {"type": storage}} for b in (2, 3, 4)),
        ])
        forms = "".join(f"const FORM_{name.upper()}: u32 = {form}u;\n" for name, (_, form) in FORMS.items())
        self.kernel = self.compute.kernel(
            Generated("<generated: kernel forms>", forms), PARAMS.generated(), SPAN.generated(), SOURCE,
            label="perspective", fix=FIX,
            layout=device.create_pipeline_layout(label="perspective", bind_group_layouts=[self.layout]))

    def pipeline(self, kernel: str) -> wgpu.GPUComputePipeline:
        """The pipeline of a kernel: its own entry point, or the shared one specialised to its form."""
        if kernel in FORMS:
            entry, form = FORMS[kernel]
            return self.kernel.pipeline(entry, {"FORM": form})
        return self.kernel.pipeline(kernel)

    def outputs(self, spans: Spans) -> Outputs:
        """Output buffers for ``spans`` (several dispatches may share them, e.g. for timing)."""
        pixels = spans.count * spans.length
        what = f"{spans.count} spans of {spans.length} pixels"
        return Outputs(self.compute.storage(16 * spans.count, f"perspective:starts of {what}", FEWER),
                       self.compute.storage(8 * pixels, f"perspective:uv of {what}", FEWER),
                       self.compute.storage(4 * pixels, f"perspective:flags of {what}", FEWER))

    def prepare(self, name: str, coefficients: np.ndarray, spans: Spans, outputs: Outputs | None = None) -> Dispatch:
        """Inputs, bind group and dispatches of method ``name`` on ``spans`` (into ``outputs``, or new ones)."""
        method = METHODS[name]
        if not method.on_gpu:
            raise ValueError(f"method {name} has no GPU kernel")
        what = f"{spans.count} spans of {spans.length} pixels"
        threads = method.threads_per_span(spans.length)
        if threads == 0:  # one thread per pixel: x along the span, y over the spans
            steps = [("span_setup", (spans.count,))] if method.kernel in AFTER_SPAN_SETUP else []
            steps.append((method.kernel, (spans.length, spans.count)))
        else:
            steps = [(method.kernel, (spans.count * threads,))]
        counts = [self.compute.check_workgroups(workgroups(t, (WORKGROUP,)), what, FEWER) for _, t in steps]
        out = outputs or self.outputs(spans)
        params = self.compute.uniform(pack_params(method, coefficients, spans), "perspective:params")
        span_buffer = self.compute.storage(pack_spans(method, coefficients, spans), f"perspective:spans of {what}",
                                           FEWER)
        group = self.compute.bind_group(self.layout, dict(enumerate((params, span_buffer, out.starts, out.uv,
                                                                     out.flags))), "perspective")
        return Dispatch(self, group, [(self.pipeline(e), c) for (e, _), c in zip(steps, counts)], out, spans)

    def run(self, name: str, coefficients: np.ndarray, spans: Spans) -> Result:
        dispatch = self.prepare(name, coefficients, spans)
        encoder = self.compute.encoder(f"perspective:{name}")
        dispatch.record(encoder)
        self.compute.submit(encoder)
        return dispatch.read()


@dataclass
class Outputs:
    starts: wgpu.GPUBuffer  # per-span constants (span_setup -> span)
    uv: wgpu.GPUBuffer
    flags: wgpu.GPUBuffer


@dataclass
class Dispatch:
    kernels: Kernels
    group: wgpu.GPUBindGroup
    steps: list[tuple[wgpu.GPUComputePipeline, tuple[int, int, int]]]
    outputs: Outputs
    spans: Spans

    def record(self, encoder: wgpu.GPUCommandEncoder, timestamp_writes: dict | None = None) -> None:
        """One compute pass with the method's dispatches (a core.pass_timing recorder)."""
        compute = encoder.begin_compute_pass(label="perspective", timestamp_writes=timestamp_writes)
        compute.set_bind_group(0, self.group)
        for pipeline, groups in self.steps:
            compute.set_pipeline(pipeline)
            compute.dispatch_workgroups(*groups)
        compute.end()

    def read(self) -> Result:
        compute = self.kernels.compute
        shape = (self.spans.count, self.spans.length)
        uv = compute.read(self.outputs.uv, 2 * self.spans.count * self.spans.length).reshape(*shape, 2)
        flagged = compute.read(self.outputs.flags, self.spans.count * self.spans.length, np.uint32).reshape(shape) != 0
        return Result(uv[..., 0].copy(), uv[..., 1].copy(), flagged)
