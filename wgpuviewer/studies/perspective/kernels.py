"""The methods as WGSL compute kernels (``wgsl/studies/perspective/kernels.wgsl``), run on spans and timed.

One shader module holds every kernel; they share one bind group layout (the Params uniform, the spans, the per-span
constants, the uv and flag outputs). ``Kernels.prepare`` uploads one method's inputs and returns a ``Dispatch`` that
records the method's pass (for timing) and reads its output back as a ``methods.Result``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import wgpu

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import Gpu
from wgpuviewer.core.wgsl import Generated, compose

from .geometry import Spans, defined_range
from .methods import METHODS, Method, Result, fixed_setup, split

SOURCE = "studies/perspective/kernels.wgsl"
#: Kernels that are forms of a shared entry point (one thread per pixel, or one per span walking it), with the
#: value of its pipeline-overridable FORM (generated into the module as FORM_* constants).
FORMS = {"direct": ("per_pixel", 0), "span": ("per_pixel", 1), "incremental": ("sequential", 2),
         "reanchor": ("sequential", 3), "kahan": ("sequential", 4), "double_single": ("sequential", 5),
         "fixed16_16": ("sequential", 6)}
WORKGROUP = 64
MAX_GROUPS = 65535  # per dispatch dimension
PARAMS_SIZE = 6 * 16 + 16  # six vec4 + span_length, span_count, param, one (common.wgsl's Params)
SPAN_STRIDE = 32  # common.wgsl's Span


def _groups(threads: int, rows: int = 1) -> tuple[int, int, int]:
    """Workgroups for ``threads`` along x (and ``rows`` along y)."""
    return max(-(-threads // WORKGROUP), 1), rows, 1


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
    """The study's shader module and its pipelines (compiled on first use) for one device."""

    def __init__(self, gpu: Gpu):
        self.gpu = gpu
        device = gpu.device
        forms = "".join(f"const FORM_{name.upper()}: u32 = {form}u;\n" for name, (_, form) in FORMS.items())
        self.source = compose(Generated("<generated: kernel forms>", forms), SOURCE)
        self.module = device.create_shader_module(label="perspective", code=self.source.code)
        C = wgpu.ShaderStage.COMPUTE
        storage = wgpu.BufferBindingType.storage
        self.layout = device.create_bind_group_layout(label="perspective", entries=[
            {"binding": 0, "visibility": C, "buffer": {"type": wgpu.BufferBindingType.uniform}},
            {"binding": 1, "visibility": C, "buffer": {"type": wgpu.BufferBindingType.read_only_storage}},
            *({"binding": b, "visibility": C, "buffer": {"type": storage}} for b in (2, 3, 4)),
        ])
        self.pipeline_layout = device.create_pipeline_layout(label="perspective", bind_group_layouts=[self.layout])
        self._pipelines: dict[str, wgpu.GPUComputePipeline] = {}

    def pipeline(self, kernel: str) -> wgpu.GPUComputePipeline:
        """The pipeline of a kernel: its own entry point, or the shared one specialised to its form."""
        if kernel not in self._pipelines:
            stage = {"module": self.module, "entry_point": kernel}
            if kernel in FORMS:
                entry, form = FORMS[kernel]
                stage = {**stage, "entry_point": entry, "constants": {"FORM": form}}
            try:
                self._pipelines[kernel] = self.gpu.device.create_compute_pipeline(
                    label=f"perspective:{kernel}", layout=self.pipeline_layout, compute=stage)
            except (wgpu.GPUValidationError, wgpu.GPUPipelineError) as exc:
                raise UserError(f"perspective kernel {kernel} failed to build on {self.gpu.summary}: "
                                f"{self.source.locate(str(exc))}") from None
        return self._pipelines[kernel]

    def outputs(self, spans: Spans) -> Outputs:
        """Output buffers for ``spans`` (several dispatches may share them, e.g. for timing)."""
        device = self.gpu.device
        pixels = spans.count * spans.length
        limit = min(device.limits["max-storage-buffer-binding-size"], device.limits["max-buffer-size"])
        if pixels * 8 > limit:
            raise UserError(f"{spans.count} spans of {spans.length} pixels need {pixels * 8} bytes of uv output, "
                            f"more than this adapter's storage buffer limit {limit}; use fewer spans")
        U = wgpu.BufferUsage
        return Outputs(device.create_buffer(label="perspective:starts", size=16 * spans.count, usage=U.STORAGE),
                       device.create_buffer(label="perspective:uv", size=8 * pixels, usage=U.STORAGE | U.COPY_SRC),
                       device.create_buffer(label="perspective:flags", size=4 * pixels, usage=U.STORAGE | U.COPY_SRC))

    def prepare(self, name: str, coefficients: np.ndarray, spans: Spans, outputs: Outputs | None = None) -> Dispatch:
        """Inputs, bind group and dispatches of method ``name`` on ``spans`` (into ``outputs``, or new ones)."""
        method = METHODS[name]
        device = self.gpu.device
        out = outputs or self.outputs(spans)
        U = wgpu.BufferUsage
        params = device.create_buffer_with_data(label="perspective:params", usage=U.UNIFORM,
                                                data=pack_params(method, coefficients, spans))
        span_buffer = device.create_buffer_with_data(label="perspective:spans", usage=U.STORAGE,
                                                     data=pack_spans(method, coefficients, spans))
        group = device.create_bind_group(layout=self.layout, entries=[
            {"binding": b, "resource": {"buffer": buf}}
            for b, buf in enumerate((params, span_buffer, out.starts, out.uv, out.flags))
        ])
        threads = method.threads_per_span(spans.length)
        if threads == 0:  # one thread per pixel: x along the span, y over the spans
            steps = [("span_setup", _groups(spans.count))] if method.kernel == "span" else []
            steps.append((method.kernel, _groups(spans.length, spans.count)))
        else:
            steps = [(method.kernel, _groups(spans.count * threads))]
        for _, groups in steps:
            if max(groups) > MAX_GROUPS:
                raise UserError(f"{spans.count} spans of {spans.length} pixels need {groups} workgroups, more than "
                                f"{MAX_GROUPS} per dimension; use fewer spans")
        return Dispatch(self, group, [(self.pipeline(e), g) for e, g in steps], out, spans)

    def run(self, name: str, coefficients: np.ndarray, spans: Spans) -> Result:
        dispatch = self.prepare(name, coefficients, spans)
        encoder = self.gpu.device.create_command_encoder(label=f"perspective:{name}")
        dispatch.record(encoder)
        self.gpu.device.queue.submit([encoder.finish()])
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
        queue = self.kernels.gpu.device.queue
        shape = (self.spans.count, self.spans.length)
        uv = np.frombuffer(queue.read_buffer(self.outputs.uv), np.float32).reshape(*shape, 2)
        flagged = np.frombuffer(queue.read_buffer(self.outputs.flags), np.uint32).reshape(shape) != 0
        return Result(uv[..., 0].copy(), uv[..., 1].copy(), flagged)
