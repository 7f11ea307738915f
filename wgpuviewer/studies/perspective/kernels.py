"""The methods as WGSL compute kernels (``wgsl/studies/perspective/kernels.wgsl``), run on spans and timed.

One shader module holds every kernel; they share one bind group layout (the Params uniform, the spans, the per-span
constants, the uv and flag outputs). ``Kernels.prepare`` uploads one method's inputs and returns a ``Dispatch`` that
records the method's pass (for timing) and reads its output back as a ``methods.Result``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import wgpu

from wgpuviewer.core.compute import compute_for, workgroups
from wgpuviewer.core.gpu import Gpu
from wgpuviewer.core.wgsl import Generated

from .geometry import Spans, defined_range
from .methods import METHODS, Method, Result, fixed_setup, split

SOURCE = "studies/perspective/kernels.wgsl"
#: Kernels that are forms of a shared entry point (one thread per pixel, or one per span walking it), with the
#: value of its pipeline-overridable FORM (generated into the module as FORM_* constants).
FORMS = {"direct": ("per_pixel", 0), "span": ("per_pixel", 1), "incremental": ("sequential", 2),
         "reanchor": ("sequential", 3), "kahan": ("sequential", 4), "double_single": ("sequential", 5),
         "fixed16_16": ("sequential", 6)}
WORKGROUP = 64  # @workgroup_size of every kernel
#: What a user can do when a kernel does not build on their adapter, or the spans do not fit its limits.
FIX = "run on another adapter (--backend)"
FEWER = "use fewer spans"
PARAMS_SIZE = 6 * 16 + 16  # six vec4 + span_length, span_count, param, one (common.wgsl's Params)
SPAN_STRIDE = 32  # common.wgsl's Span


def pack_params(method: Method, coefficients: np.ndarray, spans: Spans) -> bytes:
    k64 = np.asarray(coefficients, np.float64)
    k = k64.astype(np.float32)
    columns = np.zeros((4, 4), np.float32)  # a, b, c, a_lo
    columns[0, :3], columns[1, :3], columns[2, :3] = k[:, 0], k[:, 1], k[:, 2]
    columns[3, :3] = split(k64)[1][:, 0]
    steps, ratio = np.zeros(4, np.int32), np.zeros(4, np.float32)
    if method.kernel == "fixed16_16":
        fx = fixed_setup(k64, spans)
        steps[:3], ratio[:2] = fx.steps, fx.ratio
    tail = np.array([spans.length, spans.count, method.param], np.uint32).tobytes() + np.float32(1.0).tobytes()
    return columns.tobytes() + steps.tobytes() + ratio.tobytes() + tail


def pack_spans(method: Method, coefficients: np.ndarray, spans: Spans) -> np.ndarray:
    data = np.zeros((spans.count, SPAN_STRIDE // 4), np.int32)
    data[:, 0], data[:, 1] = spans.x0, spans.y
    data[:, 2], data[:, 3] = defined_range(coefficients, spans)
    if method.kernel == "fixed16_16":
        data[:, 4:7] = fixed_setup(coefficients, spans).starts.T
    return data


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
            Generated("<generated: kernel forms>", forms), SOURCE, label="perspective", fix=FIX,
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
        what = f"{spans.count} spans of {spans.length} pixels"
        threads = method.threads_per_span(spans.length)
        if threads == 0:  # one thread per pixel: x along the span, y over the spans
            steps = [("span_setup", (spans.count,))] if method.kernel == "span" else []
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
        """One compute pass with the method's dispatches (a core.timing recorder)."""
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
