"""GPU paths of the map kinds: drive the WGSL compute kernels in ``wgsl/maps/`` (through ``core.compute``).

Maps travel as row-major f32 storage buffers (exact texel values, no sampler or format conversion) and are read
back whole. Every map function holds the device's lock, so that the batch tool's worker threads can share the
single device.
"""

from __future__ import annotations

import functools

import numpy as np

from wgpuviewer.core.compute import compute_for
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import allocating, get_gpu
from wgpuviewer.core.structs import Struct
from wgpuviewer.core.wgsl import Module, compose

from . import cpu

#: What a user can do when a kernel fails or does not fit on their adapter.
FIX = "use --backend cpu"
_WG = (8, 8, 1)  # @workgroup_size of every kernel


#: Each kernel's uniform P (``common/map_buffers.wgsl``), generated into its module.
PARAMS = {
    "normal.wgsl": Struct("Params", [
        ("width", "u32"), ("height", "u32"), ("border", "u32"),  # border: the Sobel border (common/border.wgsl)
        ("strength", "f32"), ("ysign", "f32")]),  # ysign: +1 OpenGL (y towards row 0), -1 DirectX
    "complexity.wgsl": Struct("Params", [
        ("width", "u32"), ("height", "u32"), ("border", "u32"), ("ksize", "u32"),  # ksize: 3 or 5
        ("radius", "u32"),  # dilation radius = (kernel // 2) * iterations
        ("wrap_dilate", "u32"),  # 1: dilation wraps (repeat); 0: window clamped to the image (OpenCV's default)
        ("levels", "u32"), ("gamma", "f32"),
        ("step", "f32")]),  # f32(1 / (levels - 1)), as numpy computes it
    "maxmip.wgsl": Struct("Params", [("src_size", "vec2u"), ("dst_size", "vec2u")]),  # (w, h) of child, parent
    "distance.wgsl": Struct("Params", [
        ("width", "u32"), ("height", "u32"), ("slices", "u32"), ("subcells", "u32"),  # subcells: K
        ("sw", "f32"),  # S * W: metric length of the whole depth range t in [0, 1]
        ("sy", "f32"),  # W / H: metric height of one texel row
        ("dz", "f32"),  # metric thickness of one slice
        ("grow", "f32"),  # every voxel box is grown by this on each side (maptools.distance.BOX_GROW)
        ("margin", "f32")]),  # subtracted from every stored distance
    "distance_refined.wgsl": Struct("Params", [
        ("width", "u32"), ("height", "u32"), ("slices", "u32"), ("subcells", "u32"),
        ("count", "u32"),  # columns in the list
        ("levels", "u32"),  # window levels (window_tops)
        ("bands", "u32"),  # polar bands written (1 to 4), one per vec4 lane of:
        ("tan_lo", "vec4f"),  # tan of the band's least polar angle
        ("cot_hi", "vec4f"),  # cot of its largest polar angle
        ("inv_sin_hi", "vec4f"),  # 1 / sin of its largest polar angle
        ("cap", "vec4f"),  # reach / sin of its largest polar angle
        ("dz", "f32"), ("grow", "f32"), ("margin", "f32"), ("sw", "f32")]),  # as distance.wgsl's
    "cone.wgsl": Struct("Params", [
        ("width", "u32"), ("height", "u32"), ("rings", "u32"), ("sy", "f32"), ("max_ratio", "f32"),
        ("keep", "f32"),  # 1 - store margin
        ("dmin", "f32"),  # global min depth
        ("band", "f32")]),  # relative "may exit" band
}


def kernel_source(file: str) -> Module:
    """The composed module of kernel ``file`` (in ``wgsl/maps/``, with its generated Params): what the GPU runs
    and the cache key hashes."""
    return compose(PARAMS[file].generated(), f"maps/{file}")


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

    def uniform(self, file: str, values: dict):
        """The Params uniform of kernel ``file`` holding ``values`` (every field, by name)."""
        return self.compute.uniform(PARAMS[file].pack(values), f"maptools {file} params")

    def dispatch(self, encoder, file: str, entry: str, bindings: dict, w: int, h: int, d: int = 1) -> None:
        """One compute pass: ``entry`` of ``file`` over w x h (x d, one workgroup layer per slice) invocations."""
        kernel = self.compute.kernel_of(kernel_source(file), label=f"maptools {file}", fix=FIX)
        kernel.dispatch(encoder, entry, bindings, threads=(w, h, d), size=_WG)

    def encoder(self, label: str):
        return self.compute.encoder(label)

    def submit(self, encoder) -> None:
        self.compute.submit(encoder)

    def read(self, buf, count: int) -> np.ndarray:
        return self.compute.read(buf, count)


def runner(backend: str | None = None) -> MapGpu:
    return MapGpu(get_gpu(None if backend in (None, "gpu") else backend))


def _guard(*kernels: str):
    """A GPU map function of ``kernels`` (files of ``wgsl/maps/``, for the cache key): run on the shared device
    under its lock, with a wgpu error as a ``core.compute.KernelError``."""
    return functools.partial(_guarded, kernels=kernels)


def _guarded(fn, kernels: tuple[str, ...]):
    def wrapped(height, **options):
        g = runner()
        with g.compute.guard(f"{fn.__name__} kernel", FIX):
            return fn(g, np.ascontiguousarray(height, np.float32), **options)
    wrapped.__name__ = fn.__name__
    wrapped.__doc__ = fn.__doc__
    wrapped.kernels = kernels
    return wrapped


@_guard("normal.wgsl")
def normal(g: MapGpu, height: np.ndarray, *, strength: float = 1.0, y: str = "opengl", border: str = "repeat"):
    """GPU twin of cpu.normal (normal.wgsl)."""
    h, w = height.shape
    g.check_size(h, w, 3)
    src = g.storage(height, "maptools normal src")
    dst = g.storage(h * w * 12, "maptools normal dst")
    params = g.uniform("normal.wgsl", {"width": w, "height": h, "border": cpu.BORDER_CODE[border],
                                       "strength": strength, "ysign": 1.0 if y == "opengl" else -1.0})
    enc = g.encoder("maptools normal")
    g.dispatch(enc, "normal.wgsl", "main", {0: params, 1: src, 2: dst}, w, h)
    g.submit(enc)
    return g.read(dst, h * w * 3).reshape(h, w, 3)


@_guard("complexity.wgsl")
def complexity(g: MapGpu, height: np.ndarray, *, ksize: int = 3, dilate_kernel: int = 3, iterations: int = 5,
               gamma: float = 0.8, levels: int = 24, border: str = "reflect"):
    """GPU twin of cpu.complexity (complexity.wgsl: sobel_mag, dilate_h, dilate_v_finish)."""
    h, w = height.shape
    g.check_size(h, w)
    src = g.storage(height, "maptools complexity src")
    mag = g.storage(h * w * 4, "maptools complexity magnitude")
    tmp = g.storage(h * w * 4, "maptools complexity dilated rows")
    out = g.storage(h * w * 4, "maptools complexity out")
    maxbits = g.storage(np.zeros(4, np.uint32), "maptools complexity max")
    step = float(np.float32(1.0 / (levels - 1)))
    params = g.uniform("complexity.wgsl", {
        "width": w, "height": h, "border": cpu.BORDER_CODE[border], "ksize": ksize,
        "radius": cpu.dilation_radius(dilate_kernel, iterations), "wrap_dilate": 1 if border == "repeat" else 0,
        "levels": levels, "gamma": gamma, "step": step})
    enc = g.encoder("maptools complexity")
    g.dispatch(enc, "complexity.wgsl", "sobel_mag", {0: params, 1: src, 2: mag, 3: maxbits}, w, h)
    g.dispatch(enc, "complexity.wgsl", "dilate_h", {0: params, 1: mag, 2: tmp}, w, h)
    g.dispatch(enc, "complexity.wgsl", "dilate_v_finish", {0: params, 1: tmp, 2: out, 3: maxbits}, w, h)
    g.submit(enc)
    return g.read(out, h * w).reshape(h, w).astype(np.uint8)


@_guard("maxmip.wgsl")
def maxmip(g: MapGpu, height: np.ndarray):
    """GPU twin of cpu.maxmip (maxmip.wgsl, one dispatch per level)."""
    sizes = cpu.level_sizes(*height.shape)
    g.check_size(*height.shape)
    bufs = [g.storage(height, "maptools maxmip level 0")]
    enc = g.encoder("maptools maxmip")
    for k, (ph, pw) in enumerate(sizes[1:], start=1):
        sh, sw = sizes[k - 1]
        bufs.append(g.storage(ph * pw * 4, f"maptools maxmip level {k}"))
        params = g.uniform("maxmip.wgsl", {"src_size": (sw, sh), "dst_size": (pw, ph)})
        g.dispatch(enc, "maxmip.wgsl", "reduce", {0: params, 1: bufs[k - 1], 2: bufs[k]}, pw, ph)
    g.submit(enc)
    out = [height.copy()]
    for k, (ph, pw) in enumerate(sizes[1:], start=1):
        out.append(g.read(bufs[k], ph * pw).reshape(ph, pw))
    return out


# -- 3D distance maps ------------------------------------------------------------------------------------

def _check_volume(g: MapGpu, w: int, h: int, slices: int, subcells: int, volumes: int = 1) -> None:
    g.check_size(h, w)
    need = w * h * slices * 4 * volumes
    rows = w * h * subcells * slices * 4  # the plain map's row pass keeps every sub-cell row
    g.compute.check_buffer(max(need, rows), f"a {w}x{h}x{slices} volume with {subcells}x{subcells} sub-cells",
                           f"use fewer --slices or --subcells, or {FIX}")


def _plain_volume(g: MapGpu, enc, src, w: int, h: int, slices: int, height_scale: float, subcells: int, label: str):
    """Encode tops + pass_x + pass_y of distance.wgsl; returns (stored plain volume, sub-cell tops)."""
    from . import distance as dist

    k = subcells
    params = g.uniform("distance.wgsl", {
        "width": w, "height": h, "slices": slices, "subcells": k, "sw": height_scale * w, "sy": w / h,
        "dz": height_scale * w / slices, "grow": dist.BOX_GROW, "margin": dist.STORE_MARGIN})
    tops = g.storage(w * h * k * k * 4, f"maptools {label} sub-cell tops")
    rows = g.storage(w * h * k * slices * 4, f"maptools {label} row pass")
    out = g.storage(w * h * slices * 4, f"maptools {label} volume")
    g.dispatch(enc, "distance.wgsl", "tops", {0: params, 1: src, 2: tops}, w * k, h * k, 1)
    g.dispatch(enc, "distance.wgsl", "pass_x", {0: params, 1: tops, 2: rows}, w, h * k, slices)
    g.dispatch(enc, "distance.wgsl", "pass_y", {0: params, 1: rows, 2: out}, w, h, slices)
    return out, tops


@_guard("distance.wgsl")
def distance(g: MapGpu, height: np.ndarray, *, slices: int = 16, height_scale: float = 0.05, subcells: int = 4):
    """GPU twin of distance.distance (distance.wgsl)."""
    from . import distance as dist

    h, w = height.shape
    dist.check_volume(w, h, slices)
    dist.check_subcells(subcells, "distance")
    _check_volume(g, w, h, slices, subcells)
    src = g.storage(height, "maptools distance src")
    enc = g.encoder("maptools distance")
    out, _ = _plain_volume(g, enc, src, w, h, slices, height_scale, subcells, "distance")
    g.submit(enc)
    return g.read(out, w * h * slices).reshape(slices, h, w)


@_guard("distance.wgsl", "distance_refined.wgsl")
def distance_refined(g: MapGpu, height: np.ndarray, *, slices: int = 16, height_scale: float = 0.05,
                     subcells: int = 4, max_angle: float = 85.0, sectors: int = 4, bands: int = 8,
                     reach: float = 16.0, progress: bool = True):
    """GPU twin of refined.distance_refined: the plain volume (distance.wgsl), then one dispatch of
    distance_refined.wgsl per direction bin, each read back and rounded down to float16."""
    from tqdm import tqdm

    from . import distance as dist
    from . import refined as rf

    h, w = height.shape
    rf.check(w, h, slices, sectors, bands)
    dist.check_subcells(subcells, "distance_refined")
    _check_volume(g, w, h, slices, subcells, min(bands, rf.BANDS_PER_PASS))
    src = g.storage(height, "maptools distance_refined src")
    enc = g.encoder("maptools distance_refined plain")
    plain, sub_tops = _plain_volume(g, enc, src, w, h, slices, height_scale, subcells, "distance_refined")
    g.submit(enc)
    directions = rf.bins(sectors, bands, max_angle)
    lists = [rf.entries(directions[s], subcells, w / h, reach) for s in range(sectors)]  # band independent
    levels = max(e.levels for e in lists)
    n = w * h * slices
    out = np.empty((len(directions) + 1, slices, h, w), np.float16)
    lanes = min(bands, rf.BANDS_PER_PASS)
    vol = g.storage(lanes * n * 4, "maptools distance_refined band volumes")
    windows = g.storage(levels * w * h * 4, "maptools distance_refined window tops")
    passes = [(s, b0) for s in range(sectors) for b0 in range(0, bands, rf.BANDS_PER_PASS)]
    for number, (sector, b0) in enumerate(tqdm(passes, desc="distance_refined (gpu)", unit="pass",
                                               disable=None if progress else True, leave=False)):
        group = [directions[b * sectors + sector] for b in range(b0, min(b0 + rf.BANDS_PER_PASS, bands))]
        lane = [0.0] * (4 - len(group))  # bands of the group, one per vec4 lane; unused lanes 0
        p = g.uniform("distance_refined.wgsl", {
            "width": w, "height": h, "slices": slices, "subcells": subcells, "count": len(lists[sector].rho),
            "levels": levels, "bands": len(group), "tan_lo": [d.tan_lo for d in group] + lane,
            "cot_hi": [d.cot_hi for d in group] + lane, "inv_sin_hi": [1.0 / d.sin_hi for d in group] + lane,
            "cap": [reach / d.sin_hi for d in group] + lane, "dz": height_scale * w / slices,
            "grow": dist.BOX_GROW, "margin": dist.STORE_MARGIN, "sw": height_scale * w})
        cbuf = g.storage(lists[sector].packed(w, h, subcells), "maptools distance_refined columns")
        enc = g.encoder("maptools distance_refined pass")
        if number == 0:
            g.dispatch(enc, "distance_refined.wgsl", "window_tops", {0: p, 1: src, 2: windows}, w, h, levels)
        g.dispatch(enc, "distance_refined.wgsl", "main",
                   {0: p, 1: plain, 2: vol, 3: sub_tops, 4: windows, 5: cbuf}, w, h, slices)
        g.submit(enc)
        result = dist.round_down(g.read(vol, len(group) * n).astype(np.float64), np.float16)
        for i, b in enumerate(range(b0, b0 + len(group))):
            out[b * sectors + sector] = result[i * n:(i + 1) * n].reshape(slices, h, w)
    out[-1] = dist.round_down(g.read(plain, n).astype(np.float64), np.float16).reshape(slices, h, w)
    return out


@_guard("cone.wgsl")
def cone(g: MapGpu, height: np.ndarray, *, max_ratio: float = 16.0, filter: str = "bilinear"):
    """GPU twin of cone.cone (cone.wgsl: ratio, then min3x3 for filter=bilinear)."""
    from . import cone as cn

    h, w = height.shape
    cn.check(w, h, max_ratio)
    g.check_size(h, w)
    dmin = float(np.min(np.float32(1.0) - height))
    src = g.storage(height, "maptools cone src")
    raw = g.storage(h * w * 4, "maptools cone raw")
    out = g.storage(h * w * 4, "maptools cone out")
    params = g.uniform("cone.wgsl", {"width": w, "height": h, "rings": cn.ring_count(max_ratio, w, h), "sy": w / h,
                                     "max_ratio": max_ratio, "keep": 1.0 - cn.STORE_MARGIN, "dmin": dmin,
                                     "band": cn.EXIT_BAND})
    enc = g.encoder("maptools cone")
    g.dispatch(enc, "cone.wgsl", "ratio", {0: params, 1: src, 2: raw}, w, h)
    if filter == "bilinear":
        g.dispatch(enc, "cone.wgsl", "min3x3", {0: params, 1: raw, 2: out}, w, h)
    g.submit(enc)
    return g.read(out if filter == "bilinear" else raw, h * w).reshape(h, w)
