"""The map kinds' shared GPU runner: each kind's ``gpu.py`` declares its kernels (``map_kernel``: the WGSL file in
its folder and its Params) and drives them through ``MapGpu`` (``core.compute``), its map function wrapped by
``guard``.

Maps travel as row-major f32 storage buffers (exact texel values, no sampler or format conversion) and are read
back whole. Every map function holds the device's lock, so that the batch tool's worker threads can share the
single device.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer.core.compute import compute_for
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import allocating, get_gpu
from wgpuviewer.core.structs import Struct
from wgpuviewer.core.wgsl import Module, compose

#: What a user can do when a kernel fails or does not fit on their adapter.
FIX = "use --backend cpu"
_WG = (8, 8, 1)  # @workgroup_size of every kernel


@dataclass(frozen=True, eq=False)
class MapKernel:
    """One compute kernel of a map kind: its WGSL file (in the kind's folder) and its uniform ``Params``
    (``common/map_buffers.wgsl``'s ``P``), generated into its module. ``str()`` is its file name."""

    path: Path
    params: Struct

    @property
    def name(self) -> str:
        return self.path.name

    def __str__(self) -> str:
        return self.name

    def source(self) -> Module:
        """The composed module: what the GPU runs and the cache key hashes."""
        return compose(self.params.generated(), str(self.path))


#: Each kernel's uniform P by file name, filled as the kinds declare their kernels (``map_kernel``).
PARAMS: dict[str, Struct] = {}
_KERNELS: dict[str, MapKernel] = {}


def map_kernel(module_file: str, name: str, fields: list[tuple[str, str]]) -> MapKernel:
    """Declare kernel ``name``, a WGSL file beside ``module_file`` (a kind's ``__file__``), with the Params
    ``fields``; file names are unique across the kinds."""
    path = Path(module_file).with_name(name)
    known = _KERNELS.get(name)
    if known is not None and known.path != path:
        raise ValueError(f"map kernel {name} declared twice: {known.path} and {path}")
    kernel = MapKernel(path, Struct("Params", fields))
    _KERNELS[name], PARAMS[name] = kernel, kernel.params
    return kernel


def kernel_source(kernel: MapKernel | str) -> Module:
    """The composed module of a kernel (or of a declared kernel's file name)."""
    return (kernel if isinstance(kernel, MapKernel) else _KERNELS[kernel]).source()


class MapGpu:
    """The map kernels on one device: its ``Compute`` with maptools' kernel folder, workgroup size and fix."""

    def __init__(self, gpu):
        self.gpu = gpu
        self.compute = compute_for(gpu)
        self.device = gpu.device

    # -- resources ---------------------------------------------------------------------------------
    def check_size(self, h: int, w: int, floats_per_texel: int = 1) -> None:
        dim = self.device.limits["max-texture-dimension-2d"]
        if h > dim or w > dim:
            raise UserError(f"height map is {w}x{h}, larger than this adapter's max texture dimension {dim}; "
                            f"downscale it or {FIX}")
        self.compute.check_buffer(h * w * 4 * floats_per_texel, f"a {w}x{h} height map", f"downscale it or {FIX}")

    def storage(self, data_or_size, label: str):
        """A storage buffer (``core.compute``'s limits checked); the adapter out of memory is a UserError."""
        size = data_or_size if isinstance(data_or_size, int) else memoryview(data_or_size).nbytes
        with allocating(self.gpu, label, size, FIX):
            return self.compute.storage(data_or_size, label, FIX)

    def uniform(self, kernel: MapKernel, values: dict):
        """The Params uniform of ``kernel`` holding ``values`` (every field, by name)."""
        return self.compute.uniform(kernel.params.pack(values), f"maptools {kernel} params")

    def dispatch(self, encoder, kernel: MapKernel, entry: str, bindings: dict, w: int, h: int, d: int = 1) -> None:
        """One compute pass: ``entry`` of ``kernel`` over w x h (x d, one workgroup layer per slice) invocations."""
        compiled = self.compute.kernel_of(kernel.source(), label=f"maptools {kernel}", fix=FIX)
        compiled.dispatch(encoder, entry, bindings, threads=(w, h, d), size=_WG)

    def encoder(self, label: str):
        return self.compute.encoder(label)

    def submit(self, encoder) -> None:
        self.compute.submit(encoder)

    def read(self, buf, count: int) -> np.ndarray:
        return self.compute.read(buf, count)


def runner(backend: str | None = None) -> MapGpu:
    return MapGpu(get_gpu(None if backend in (None, "gpu") else backend))


def guard(*kernels: MapKernel):
    """A kind's GPU map function running ``kernels`` (all it dispatches: the cache key hashes them): run on the
    shared device under its lock, with a wgpu error as a ``core.compute.KernelError``."""
    return functools.partial(_guarded, kernels=kernels)


def _guarded(fn, kernels: tuple[MapKernel, ...]):
    def wrapped(height, **options):
        g = runner()
        with g.compute.guard(f"{fn.__name__} kernel", FIX):
            return fn(g, np.ascontiguousarray(height, np.float32), **options)
    wrapped.__name__ = fn.__name__
    wrapped.__doc__ = fn.__doc__
    wrapped.kernels = kernels
    return wrapped
