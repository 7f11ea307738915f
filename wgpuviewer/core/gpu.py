"""GPU acquisition: pick an adapter for a backend, create (and cache) one device per backend.

`auto` prefers a hardware adapter (discrete, then integrated) and falls back to a software one
(Mesa lavapipe/llvmpipe, WARP, SwiftShader) with a one-line notice on stderr. The first adapter request prepares
what the drivers read from the environment (``prepare_driver_environment``), for the CLIs and the Python API alike.

GPU memory: every texture and buffer the project creates goes through ``allocating``, so an adapter out of memory
is a ``UserError`` naming what was being made, the bytes it needed and the fix, never an internal error.
"""

from __future__ import annotations

import contextlib
import sys
import threading
from dataclasses import dataclass, field

import cv2
import numpy as np
import wgpu

from . import env
from .errors import NoAdapterError, UserError

#: CLI name -> wgpu backend_type as reported in ``adapter.info``.
BACKENDS = {"vulkan": "Vulkan", "metal": "Metal", "dx12": "D3D12", "gl": "OpenGL"}
BACKEND_CHOICES = ("auto", *BACKENDS)
BACKEND_ENV = env.BACKEND.name

#: Optional features we use when the adapter has them.
WANTED_FEATURES = ("float32-filterable", "timestamp-query", "shader-f64")

_TYPE_RANK = {"DiscreteGPU": 0, "IntegratedGPU": 1, "VirtualGPU": 2, "Unknown": 3, "CPU": 4}

NO_ADAPTER_FIX = (
    "install a GPU driver with Vulkan/Metal/D3D12/OpenGL support, or the software Vulkan adapter "
    "(Debian/Ubuntu: sudo apt-get install mesa-vulkan-drivers)"
)


def resolve_backend(backend: str | None) -> str:
    """CLI/env backend name -> one of BACKEND_CHOICES (argument wins over the environment, parsed by core.env)."""
    if not backend:
        return env.BACKEND.value()
    name = backend.strip().lower()
    if name not in BACKEND_CHOICES:
        raise UserError(f"--backend: unknown backend {name!r}; expected one of {', '.join(BACKEND_CHOICES)}")
    return name


def list_adapters() -> list[wgpu.GPUAdapter]:
    env.prepare_driver_environment()  # the API's first GPU use is as quiet as the CLIs'
    return list(wgpu.gpu.enumerate_adapters_sync())


def offered_backends(adapters: list[wgpu.GPUAdapter] | None = None) -> list[str]:
    """The backend names (``BACKENDS``' keys) this machine has adapters for, in ``BACKENDS``' order."""
    kinds = {a.info.get("backend_type") for a in (list_adapters() if adapters is None else adapters)}
    return [name for name, kind in BACKENDS.items() if kind in kinds]


def is_software(adapter: wgpu.GPUAdapter) -> bool:
    return adapter.info.get("adapter_type") == "CPU"


def choose_adapter(backend: str | None = None, *, quiet: bool = False) -> wgpu.GPUAdapter:
    """The adapter for a backend name; raises NoAdapterError with the fix when there is none."""
    name = resolve_backend(backend)
    adapters = list_adapters()
    offered = offered_backends(adapters)
    if name != "auto":
        adapters = [a for a in adapters if a.info.get("backend_type") == BACKENDS[name]]
    if not adapters and offered:  # another backend would do
        raise NoAdapterError(f"no GPU adapter found for backend {name!r} (this machine offers "
                             f"{', '.join(offered)}); use --backend {offered[0]} or --backend auto")
    if not adapters:
        where = "" if name == "auto" else f" for backend {name!r}"
        raise NoAdapterError(f"no GPU adapter found{where}; {NO_ADAPTER_FIX}")
    # Stable choice: best adapter type first; Vulkan/Metal/D3D12 before OpenGL (better feature coverage).
    adapters.sort(key=lambda a: (_TYPE_RANK.get(a.info.get("adapter_type"), 3), a.info.get("backend_type") == "OpenGL"))
    chosen = adapters[0]
    if is_software(chosen) and not quiet:
        print(f"notice: no hardware GPU adapter; using software adapter {chosen.summary}", file=sys.stderr)
    return chosen


@dataclass
class Gpu:
    """A device and what we know about it; shared by the renderer, the probe and maptools."""

    adapter: wgpu.GPUAdapter
    device: wgpu.GPUDevice
    features: frozenset[str] = field(default_factory=frozenset)
    #: Per-device caches (the compute kernels: ``core.compute.compute_for``; the renderer's pipelines), keyed by
    #: their users.
    cache: dict = field(default_factory=dict)
    #: Serialises GPU work of threads that share the device (the maptools batch workers); re-entrant.
    lock: threading.RLock = field(default_factory=threading.RLock)

    @property
    def summary(self) -> str:
        return self.adapter.summary

    @property
    def software(self) -> bool:
        return is_software(self.adapter)

    @property
    def depth_format(self) -> str:
        """Filterable format for height/depth data: float32 where the adapter can filter it."""
        return "r32float" if "float32-filterable" in self.features else "r16float"


_devices: dict[str, Gpu] = {}


def get_gpu(backend: str | None = None, *, quiet: bool = False) -> Gpu:
    """One cached device per backend name (creating devices is slow, and resources must share one)."""
    name = resolve_backend(backend)
    if name not in _devices:
        adapter = choose_adapter(name, quiet=quiet)
        features = frozenset(f for f in WANTED_FEATURES if f in adapter.features)
        device = adapter.request_device_sync(label="wgpuviewer", required_features=sorted(features))
        _devices[name] = Gpu(adapter, device, features)
    return _devices[name]


def describe_adapters(backend: str | None = None) -> str:
    """Text for `wgpuviewer info`."""
    lines = ["adapters:"]
    adapters = list_adapters()
    for a in adapters:
        info = a.info
        lines.append(f"  - {a.summary}  [type {info.get('adapter_type')}, backend {info.get('backend_type')}]")
    if not adapters:
        lines.append(f"  (none) -- {NO_ADAPTER_FIX}")
        return "\n".join(lines)
    lines.append(f"backends: {', '.join(offered_backends(adapters))}")
    chosen = choose_adapter(backend, quiet=True)
    lines.append(f"chosen ({resolve_backend(backend)}): {chosen.summary}")
    have = sorted(f for f in WANTED_FEATURES if f in chosen.features)
    missing = sorted(set(WANTED_FEATURES) - set(have))
    lines.append(f"relevant features: {', '.join(have) or 'none'}" + (f"; missing: {', '.join(missing)}" if missing else ""))
    limits = chosen.limits
    shown = ("max-texture-dimension-2d", "max-texture-dimension-3d", "max-storage-buffer-binding-size")
    lines.append("limits: " + ", ".join(f"{k}={limits[k]}" for k in shown))
    return "\n".join(lines)


# --- resource helpers shared by the renderer, the probe and the viewer ------------------------

_TEXEL = {  # format -> (numpy dtype, channels)
    "r32float": (np.float32, 1),
    "r16float": (np.float16, 1),
    "rg32float": (np.float32, 2),
    "rgba16float": (np.float16, 4),
    "rgba32float": (np.float32, 4),
    "rgba8unorm": (np.uint8, 4),
    "rgba8unorm-srgb": (np.uint8, 4),
}


#: Texels converted and uploaded per step: the conversion's temporaries stay small at any texture size.
BAND_TEXELS = 1 << 16


def _texel_band(band: np.ndarray, dtype, channels: int) -> np.ndarray:
    a = np.asarray(band, np.float32)
    if a.ndim == 2:
        a = a[:, :, None]
    out = np.ones(a.shape[:2] + (channels,), dtype)  # missing channels (alpha) are 1
    c = min(a.shape[2], channels)
    if dtype == np.uint8:
        out[:, :, :c] = np.clip(np.rint(a[:, :, :c] * 255.0), 0, 255)
    else:
        out[:, :, :c] = a[:, :, :c]
    return out


def _bands(h: int, w: int):
    step = max(1, BAND_TEXELS // max(w, 1))
    for row in range(0, h, step):
        yield row, min(row + step, h)


def to_texel_data(data: np.ndarray, fmt: str) -> np.ndarray:
    """(H, W) or (H, W, C) floats in [0, 1] -> contiguous texel array for ``fmt`` (converted in row bands)."""
    dtype, channels = _TEXEL[fmt]
    a = np.asarray(data)
    out = np.empty(a.shape[:2] + (channels,), dtype)
    for r0, r1 in _bands(*a.shape[:2]):
        out[r0:r1] = _texel_band(a[r0:r1], dtype, channels)
    return out


def format_bytes(n: float) -> str:
    """A byte count for messages: '512 B', '3.0 MiB', '4.0 GiB'."""
    for unit in ("B", "KiB", "MiB", "GiB"):
        if n < 1024:
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} TiB"


def _out_of_memory(error: Exception) -> bool:
    """Whether wgpu reports the adapter out of memory: GPUOutOfMemoryError, or (wgpu-native on Vulkan) a
    validation error 'Not enough memory left' raised by the creating call."""
    return isinstance(error, wgpu.GPUOutOfMemoryError) or (
        isinstance(error, wgpu.GPUValidationError) and "memory" in str(error).lower())


@contextlib.contextmanager
def allocating(gpu: Gpu, what: str, nbytes: int, fix: str):
    """Create GPU resources for ``what`` (``nbytes`` of GPU memory) inside: the adapter running out of memory is a
    UserError ``WHAT needs N GiB of GPU memory, more than ADAPTER could allocate; FIX``; other errors pass."""
    try:
        yield
    except (wgpu.GPUOutOfMemoryError, wgpu.GPUValidationError) as error:
        if not _out_of_memory(error):
            raise
        raise UserError(f"{what} needs {format_bytes(nbytes)} of GPU memory, more than {gpu.summary} could "
                        f"allocate; {fix}") from None


def texel_bytes(fmt: str) -> int:
    """Bytes per texel of a format ``create_texture`` uploads."""
    dtype, channels = _TEXEL[fmt]
    return np.dtype(dtype).itemsize * channels


def check_texture_size(gpu: Gpu, w: int, h: int, what: str, fix: str) -> None:
    """A UserError when a w x h 2D texture exceeds the adapter's limit per side (checked before any data is made)."""
    limit = gpu.device.limits["max-texture-dimension-2d"]
    if max(w, h) > limit:
        raise UserError(f"{what}: texture of {w}x{h} exceeds this adapter's limit of {limit} texels per side; {fix}")


#: What a user can do about a texture too large for the adapter.
SMALLER_TEXTURE = "use a smaller texture"


def create_texture(gpu: Gpu, levels, fmt: str, label: str) -> wgpu.GPUTexture:
    """A sampled 2D texture from a mip chain (``levels[0]`` is the base level; a list, or ``mip_chain``'s lazy
    chain). Each level is converted and uploaded in row bands, so no full-size texel copy is ever made: peak
    memory is the caller's base level plus the next level (a quarter of it). Too large for the adapter (limit
    per side, memory): a UserError naming ``label``."""
    base = levels[0]
    h, w = base.shape[:2]
    check_texture_size(gpu, w, h, label, SMALLER_TEXTURE)
    count = len(levels)
    nbytes = sum(max(w >> m, 1) * max(h >> m, 1) for m in range(count)) * texel_bytes(fmt)
    with allocating(gpu, label, nbytes, SMALLER_TEXTURE):
        texture = gpu.device.create_texture(
            label=label,
            size=(w, h, 1),
            format=fmt,
            usage=wgpu.TextureUsage.TEXTURE_BINDING | wgpu.TextureUsage.COPY_DST,
            mip_level_count=count,
        )
    dtype, channels = _TEXEL[fmt]
    for level, data in enumerate(levels):
        lh, lw = data.shape[:2]
        for r0, r1 in _bands(lh, lw):
            texels = _texel_band(data[r0:r1], dtype, channels)
            gpu.device.queue.write_texture(
                {"texture": texture, "mip_level": level, "origin": (0, r0, 0)},
                texels,
                {"offset": 0, "bytes_per_row": texels.strides[0], "rows_per_image": r1 - r0},
                (lw, r1 - r0, 1),
            )
    return texture


class MipChain:
    """Average (box-filtered) mip chain down to 1x1, odd sizes rounding down as WebGPU mips do; lazy: each level
    is computed from the one before when iterated, and only those two are alive at a time."""

    def __init__(self, data: np.ndarray):
        self.base = np.asarray(data, np.float32)
        self._count = int(max(self.base.shape[:2])).bit_length()

    def __len__(self) -> int:
        return self._count

    def __iter__(self):
        level = self.base
        yield level
        while max(level.shape[:2]) > 1:
            h, w = level.shape[:2]
            level = cv2.resize(level, (max(w // 2, 1), max(h // 2, 1)), interpolation=cv2.INTER_AREA)
            if level.ndim < self.base.ndim:  # cv2 drops a trailing channel axis of size 1
                level = level[..., None]
            yield level

    def __getitem__(self, index: int) -> np.ndarray:
        if index < 0:
            index += self._count
        for i, level in enumerate(self):
            if i == index:
                return level
        raise IndexError(index)


def mip_chain(data: np.ndarray) -> MipChain:
    """The (lazy) mip chain of ``data``: see ``MipChain``."""
    return MipChain(data)


def fullscreen_pipeline(device: wgpu.GPUDevice, label: str, code: str, entries: list[dict],
                        target_format: str) -> tuple[wgpu.GPUBindGroupLayout, wgpu.GPURenderPipeline]:
    """(bind-group layout, pipeline) of a fullscreen pass: ``code`` includes ``common/fullscreen.wgsl`` (its
    ``vs_main``, draw 3 vertices) and defines ``fs_main``; ``entries``: the layout entries of @group(0)."""
    module = device.create_shader_module(label=label, code=code)
    layout = device.create_bind_group_layout(label=label, entries=entries)
    pipeline = device.create_render_pipeline(
        label=label,
        layout=device.create_pipeline_layout(label=label, bind_group_layouts=[layout]),
        vertex={"module": module, "entry_point": "vs_main"},
        primitive={"topology": "triangle-list"},
        fragment={"module": module, "entry_point": "fs_main", "targets": [{"format": target_format}]},
    )
    return layout, pipeline
