"""Compute kernels: compose, compile (errors located at file:line), check limits, bind, dispatch, read back.

``compute_for(gpu)`` is the device's one ``Compute`` (kept in ``Gpu.cache``): its kernels and pipeline layouts, made
once per device, behind the device's lock (``Gpu.lock``: threads such as the maptools batch workers share a device).
A ``Kernel`` is one composed module (WGSL files and ``Generated`` pieces); its ``source_hash`` names exactly the code
the GPU compiles. Users: maptools, the probe and filter probe, the perspective study's kernels.
"""

from __future__ import annotations

import contextlib
import hashlib
from collections.abc import Iterator, Mapping, Sequence

import numpy as np
import wgpu

from .errors import UserError
from .gpu import Gpu
from .wgsl import Generated, Module, compose

_CACHE_KEY = "compute"
#: Buffer usage of every storage buffer: bound to kernels, written from numpy, read back.
STORAGE = wgpu.BufferUsage.STORAGE | wgpu.BufferUsage.COPY_SRC | wgpu.BufferUsage.COPY_DST


class KernelError(UserError):
    """A kernel failed to compile, validate or run on this adapter; the message names the adapter and the fix."""


class LimitError(UserError):
    """A buffer or a dispatch beyond this adapter's limits; the message names the limit and the fix."""


def source_hash(module: Module) -> str:
    """sha256 of a composed module's code: what the GPU compiles, so any edit of a file it includes changes it."""
    return hashlib.sha256(module.code.encode()).hexdigest()


def _first_line(exc: Exception) -> str:
    lines = [t.strip() for t in str(exc).strip().splitlines() if t.strip()]
    return lines[0] if lines else type(exc).__name__


def workgroups(threads: Sequence[int], size: Sequence[int]) -> tuple[int, int, int]:
    """Workgroups covering ``threads`` (x[, y[, z]]) invocations with workgroups of ``size``."""
    t = (*threads, 1, 1)[:3]
    s = (*size, 1, 1)[:3]
    return tuple(-(-int(n) // int(k)) for n, k in zip(t, s))


class Kernel:
    """One composed module on one device; a pipeline per entry point, compiled on first use.

    ``layout``: "auto" (bind group layouts derived from the shader) or a pipeline layout of the caller.
    ``fix``: what a user can do when it fails on their adapter (e.g. "use --backend cpu")."""

    def __init__(self, compute: Compute, source: Module, label: str, fix: str, layout="auto"):
        self.compute = compute
        self.source = source
        self.source_hash = source_hash(source)
        self.label = label
        self.fix = fix
        self.layout = layout
        self._module: wgpu.GPUShaderModule | None = None
        self._pipelines: dict[tuple, wgpu.GPUComputePipeline] = {}

    def pipeline(self, entry: str, constants: Mapping[str, float] | None = None) -> wgpu.GPUComputePipeline:
        """The pipeline of ``entry`` (with its pipeline-overridable ``constants``); a compile or link error is a
        KernelError at the original file:line."""
        key = (entry, tuple(sorted((constants or {}).items())))
        if key not in self._pipelines:
            device = self.compute.gpu.device
            try:
                if self._module is None:
                    self._module = device.create_shader_module(label=self.label, code=self.source.code)
                stage = {"module": self._module, "entry_point": entry}
                if constants:
                    stage["constants"] = dict(constants)
                self._pipelines[key] = device.create_compute_pipeline(
                    label=f"{self.label}:{entry}", layout=self.layout, compute=stage)
            except (wgpu.GPUValidationError, wgpu.GPUPipelineError) as exc:
                raise KernelError(f"kernel {self.label}:{entry} failed to build on {self.compute.gpu.summary}: "
                                  f"{self.source.locate(str(exc))}; {self.fix}") from None
        return self._pipelines[key]

    def bind(self, entry: str, bindings: Mapping[int, object], group: int = 0) -> wgpu.GPUBindGroup:
        """Bind group ``group`` of ``entry``'s pipeline from binding number -> resource."""
        layout = self.pipeline(entry).get_bind_group_layout(group)
        return self.compute.bind_group(layout, bindings, f"{self.label}:{entry}:{group}")

    def dispatch(self, encoder: wgpu.GPUCommandEncoder, entry: str, bindings: Mapping[int, object] | None,
                 threads: Sequence[int], size: Sequence[int] = (8, 8, 1),
                 groups: Sequence[wgpu.GPUBindGroup | None] = ()) -> None:
        """One compute pass of ``entry`` over ``threads`` invocations in workgroups of ``size`` (the kernel's
        @workgroup_size): group 0 from ``bindings`` (binding number -> resource), then ``groups`` as given (None:
        a group the kernel does not use)."""
        counts = self.compute.check_workgroups(workgroups(threads, size), f"{self.label}:{entry}", self.fix)
        pipeline = self.pipeline(entry)
        bound = ([self.bind(entry, bindings)] if bindings is not None else []) + list(groups)
        cp = encoder.begin_compute_pass(label=f"{self.label}:{entry}")
        cp.set_pipeline(pipeline)
        for index, group in enumerate(bound):
            if group is not None:
                cp.set_bind_group(index, group)
        cp.dispatch_workgroups(*counts)
        cp.end()


class Compute:
    """The compute kernels of one device and what they share: buffers, limits, submission, read-back."""

    def __init__(self, gpu: Gpu):
        self.gpu = gpu
        self.device: wgpu.GPUDevice = gpu.device
        self.lock = gpu.lock
        self._kernels: dict[tuple, Kernel] = {}
        self._layouts: dict[str, wgpu.GPUPipelineLayout] = {}

    def kernel(self, *parts: str | Generated, label: str, fix: str, layout="auto") -> Kernel:
        """The kernel composed of ``parts`` (WGSL files and generated pieces): ``kernel_of`` their module."""
        return self.kernel_of(compose(*parts), label=label, fix=fix, layout=layout)

    def kernel_of(self, source: Module, *, label: str, fix: str, layout="auto") -> Kernel:
        """The kernel of a composed module, made once per device per source (an edited file is a new kernel),
        label and layout."""
        key = (source_hash(source), label, layout)
        with self.lock:
            if key not in self._kernels:
                self._kernels[key] = Kernel(self, source, label, fix, layout)
            return self._kernels[key]

    def layout(self, groups: Sequence[Sequence[dict]], label: str) -> wgpu.GPUPipelineLayout:
        """The pipeline layout of bind groups with these layout entries (made once per device per entries)."""
        key = repr([list(g) for g in groups])
        with self.lock:
            if key not in self._layouts:
                self._layouts[key] = self.device.create_pipeline_layout(label=label, bind_group_layouts=[
                    self.device.create_bind_group_layout(label=f"{label}:{i}", entries=list(g))
                    for i, g in enumerate(groups)])
            return self._layouts[key]

    # -- limits ------------------------------------------------------------------------------------
    @property
    def max_buffer(self) -> int:
        """Largest buffer a kernel can bind as storage on this device, in bytes."""
        limits = self.device.limits
        return min(limits["max-storage-buffer-binding-size"], limits["max-buffer-size"])

    def check_buffer(self, size: int, what: str, fix: str) -> None:
        """A LimitError when ``what`` needs a storage buffer of ``size`` bytes beyond this device's limit."""
        if size > self.max_buffer:
            raise LimitError(f"{what} needs a {size}-byte buffer, more than the {self.max_buffer} bytes "
                             f"{self.gpu.summary} can bind; {fix}")

    def check_workgroups(self, counts: tuple[int, int, int], what: str, fix: str) -> tuple[int, int, int]:
        """``counts`` when each is within this device's workgroups per dimension; a LimitError otherwise."""
        limit = self.device.limits["max-compute-workgroups-per-dimension"]
        for axis, n in zip("xyz", counts):
            if n > limit:
                raise LimitError(f"{what}: {n} workgroups along {axis}, more than the {limit} {self.gpu.summary} "
                                 f"allows; {fix}")
        return counts

    def bind_group(self, layout: wgpu.GPUBindGroupLayout, bindings: Mapping[int, object],
                   label: str) -> wgpu.GPUBindGroup:
        """A bind group of ``layout``: binding number -> buffer (bound whole), sampler or texture view."""
        return self.device.create_bind_group(
            label=label, layout=layout,
            entries=[{"binding": b, "resource": {"buffer": r} if isinstance(r, wgpu.GPUBuffer) else r}
                     for b, r in sorted(bindings.items())])

    # -- buffers -----------------------------------------------------------------------------------
    def storage(self, data_or_size: np.ndarray | bytes | int, label: str, fix: str) -> wgpu.GPUBuffer:
        """A storage buffer holding ``data`` or of ``size`` bytes (zeroed; at least 4), checked against the limit."""
        size = data_or_size if isinstance(data_or_size, int) else memoryview(data_or_size).nbytes
        self.check_buffer(size, label, fix)
        if isinstance(data_or_size, int):
            return self.device.create_buffer(label=label, size=max(4, data_or_size), usage=STORAGE)
        return self.device.create_buffer_with_data(label=label, data=data_or_size, usage=STORAGE)

    def uniform(self, data: np.ndarray | bytes, label: str) -> wgpu.GPUBuffer:
        return self.device.create_buffer_with_data(label=label, data=data, usage=wgpu.BufferUsage.UNIFORM)

    def encoder(self, label: str) -> wgpu.GPUCommandEncoder:
        return self.device.create_command_encoder(label=label)

    def submit(self, encoder: wgpu.GPUCommandEncoder) -> None:
        self.device.queue.submit([encoder.finish()])

    def read(self, buffer: wgpu.GPUBuffer, count: int, dtype=np.float32) -> np.ndarray:
        """The first ``count`` values of ``buffer`` as a (writable) numpy array of ``dtype``."""
        size = count * np.dtype(dtype).itemsize
        return np.frombuffer(self.device.queue.read_buffer(buffer, 0, size), dtype).copy()

    @contextlib.contextmanager
    def guard(self, what: str, fix: str) -> Iterator[Compute]:
        """Hold the device's lock; a wgpu validation or pipeline error inside is a KernelError naming ``what``,
        the adapter and ``fix``."""
        with self.lock:
            try:
                yield self
            except (wgpu.GPUValidationError, wgpu.GPUPipelineError) as exc:
                raise KernelError(f"GPU {what} failed on {self.gpu.summary}: {_first_line(exc)}; {fix}") from None


def compute_for(gpu: Gpu) -> Compute:
    """The device's one Compute (made on first use, kept in ``gpu.cache``)."""
    with gpu.lock:
        if _CACHE_KEY not in gpu.cache:
            gpu.cache[_CACHE_KEY] = Compute(gpu)
        return gpu.cache[_CACHE_KEY]
