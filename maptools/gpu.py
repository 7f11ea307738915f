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
        ("width", "u32"), ("height", "u32"),
        ("first_slice", "u32"), ("slices", "u32"),  # the slab baked: slices [first_slice, first_slice + slices)
        ("subcells", "u32"),  # K
        ("sw", "f32"),  # S * W: metric length of the whole depth range t in [0, 1]
        ("sy", "f32"),  # W / H: metric height of one texel row
        ("dz", "f32"),  # metric thickness of one slice
        ("grow", "f32"),  # every voxel box is grown by this on each side (maptools.distance.BOX_GROW)
        ("margin", "f32")]),  # subtracted from every stored distance
    "distance_refined.wgsl": Struct("Params", [
        ("width", "u32"), ("height", "u32"), ("first_slice", "u32"), ("slices", "u32"), ("subcells", "u32"),
        ("count", "u32"),  # columns in the list
        ("levels", "u32"),  # window levels (window_tops)
        ("bands", "u32"),  # polar bands written (1 to 4), one per vec4 lane of:
        ("tan_lo", "vec4f"),  # tan of the band's least polar angle
        ("cot_hi", "vec4f"),  # cot of its largest polar angle
        ("inv_sin_hi", "vec4f"),  # 1 / sin of its largest polar angle
        ("cap", "vec4f"),  # reach / sin of its largest polar angle
        ("dz", "f32"), ("grow", "f32"), ("margin", "f32"), ("sw", "f32"),  # as distance.wgsl's
        ("visibility", "u32"),  # 1: cut each voxel's polar range by reach_cot (the paper's visibility condition)
        ("rings", "u32"),  # horizon: backward distances tested, ring n at (n + 1) * horizon_step
        ("horizon_step", "f32"), ("reach", "f32"),
        ("cot_slack", "f32")]),  # cot of the bins' angle slack (maptools.refined.COT_SLACK)
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
# The volumes are baked in slabs of consecutive slices (each slab's buffers within the adapter's storage limit):
# the sub-cell tops, the window tops and the column lists are made once, the passes run slab by slab, and each
# slab is read back into the whole volume. A slab's kernels offset their slice index by ``first_slice``.

def bake_buffers(w: int, h: int, subcells: int, lanes: int = 0) -> tuple[int, int]:
    """(bytes of the buffers made once, bytes per slice of a slab) of a w x h volume bake with K = ``subcells``:
    the sub-cell tops (K^2 floats a texel) once; per slice the row pass (K floats a texel), the volume, and for
    the refined bake ``lanes`` band volumes. Each is one storage buffer, so each must fit the binding limit."""
    once = w * h * subcells * subcells * 4
    per_slice = w * h * 4 * max(subcells, lanes, 1)
    return once, per_slice


def fitting_subcells(w: int, h: int, max_buffer: int, lanes: int = 0, most: int = 4) -> int | None:
    """The largest sub-cell count (of ``distance.SUBCELLS``, at most ``most``) whose bake of a w x h volume fits
    storage buffers of ``max_buffer`` bytes with slabs of one slice; None when none does."""
    from . import distance as dist

    for k in sorted((k for k in dist.SUBCELLS if k <= most), reverse=True):
        if max(bake_buffers(w, h, k, lanes)) <= max_buffer:
            return k
    return None


def _slab_slices(g: MapGpu, w: int, h: int, slices: int, subcells: int, lanes: int = 0) -> int:
    """Slices per slab: as many as the storage limit allows (all of them when the volume fits whole)."""
    once, per_slice = bake_buffers(w, h, subcells, lanes)
    what = f"a {w}x{h} volume with {subcells}x{subcells} sub-cells"
    fix = f"use fewer --subcells, downscale the height map or {FIX}"
    g.compute.check_buffer(once, f"{what} (its sub-cell tops)", fix)
    g.compute.check_buffer(per_slice, f"{what} (one slice)", fix)
    return max(1, min(slices, g.compute.max_buffer // per_slice))


def _slabs(slices: int, slab: int) -> list[tuple[int, int]]:
    """(first slice, slice count) of each slab."""
    return [(k0, min(slab, slices - k0)) for k0 in range(0, slices, slab)]


def _distance_params(w: int, h: int, first: int, count: int, height_scale: float, subcells: int, slices: int) -> dict:
    from . import distance as dist

    return {"width": w, "height": h, "first_slice": first, "slices": count, "subcells": subcells,
            "sw": height_scale * w, "sy": w / h, "dz": height_scale * w / slices, "grow": dist.BOX_GROW,
            "margin": dist.STORE_MARGIN}


def _subcell_tops(g: MapGpu, src, w: int, h: int, height_scale: float, subcells: int, label: str):
    """The sub-cell tops buffer (distance.wgsl ``tops``), computed and submitted."""
    k = subcells
    tops = g.storage(w * h * k * k * 4, f"maptools {label} sub-cell tops")
    params = g.uniform("distance.wgsl", _distance_params(w, h, 0, 1, height_scale, k, 1))
    enc = g.encoder(f"maptools {label} tops")
    g.dispatch(enc, "distance.wgsl", "tops", {0: params, 1: src, 2: tops}, w * k, h * k, 1)
    g.submit(enc)
    return tops


def _plain_slab(g: MapGpu, enc, tops, rows, out, w: int, h: int, first: int, count: int, slices: int,
                height_scale: float, subcells: int) -> None:
    """Encode pass_x + pass_y of distance.wgsl for slices [first, first + count) into ``out`` (the slab's
    stored plain values, indexed (slice - first, row, column))."""
    params = g.uniform("distance.wgsl", _distance_params(w, h, first, count, height_scale, subcells, slices))
    g.dispatch(enc, "distance.wgsl", "pass_x", {0: params, 1: tops, 2: rows}, w, h * subcells, count)
    g.dispatch(enc, "distance.wgsl", "pass_y", {0: params, 1: rows, 2: out}, w, h, count)


@_guard("distance.wgsl")
def distance(g: MapGpu, height: np.ndarray, *, slices: int = 16, height_scale: float = 0.05, subcells: int = 4):
    """GPU twin of distance.distance (distance.wgsl), baked in slabs of slices."""
    from . import distance as dist

    h, w = height.shape
    dist.check_volume(w, h, slices)
    dist.check_subcells(subcells, "distance")
    g.check_size(h, w)
    slab = _slab_slices(g, w, h, slices, subcells)
    src = g.storage(height, "maptools distance src")
    tops = _subcell_tops(g, src, w, h, height_scale, subcells, "distance")
    rows = g.storage(w * h * subcells * slab * 4, "maptools distance row pass")
    vol = g.storage(w * h * slab * 4, "maptools distance volume")
    out = np.empty((slices, h, w), np.float32)
    for first, count in _slabs(slices, slab):
        enc = g.encoder("maptools distance slab")
        _plain_slab(g, enc, tops, rows, vol, w, h, first, count, slices, height_scale, subcells)
        g.submit(enc)
        out[first:first + count] = g.read(vol, w * h * count).reshape(count, h, w)
    return out


@_guard("distance.wgsl", "distance_refined.wgsl")
def distance_refined(g: MapGpu, height: np.ndarray, *, slices: int = 16, height_scale: float = 0.05,
                     subcells: int = 4, max_angle: float = 85.0, sectors: int = 4, bands: int = 8,
                     reach: float = 16.0, visibility: str = "off", progress: bool = True):
    """GPU twin of refined.distance_refined, baked in slabs of slices: per slab the plain volume (distance.wgsl),
    then one dispatch of distance_refined.wgsl per azimuth sector and group of up to 4 bands, each read back and
    rounded down to float16. With the visibility condition, each sector's cut (``horizon``) first, per slab."""
    from tqdm import tqdm

    from . import distance as dist
    from . import refined as rf

    h, w = height.shape
    rf.check(w, h, slices, sectors, bands)
    dist.check_subcells(subcells, "distance_refined")
    rf.check_visibility(visibility)
    g.check_size(h, w)
    visible = visibility == "on"
    lanes = min(bands, rf.BANDS_PER_PASS)
    slab = _slab_slices(g, w, h, slices, subcells, lanes)
    directions = rf.bins(sectors, bands, max_angle)
    lists = [rf.entries(directions[s], subcells, w / h, reach) for s in range(sectors)]  # band independent
    levels = max(e.levels for e in lists)
    g.compute.check_buffer(levels * w * h * 4, f"the window tops of a {w}x{h} height map",
                           f"downscale the height map or {FIX}")
    src = g.storage(height, "maptools distance_refined src")
    tops = _subcell_tops(g, src, w, h, height_scale, subcells, "distance_refined")
    rows = g.storage(w * h * subcells * slab * 4, "maptools distance_refined row pass")
    plain = g.storage(w * h * slab * 4, "maptools distance_refined plain slab")
    vol = g.storage(lanes * w * h * slab * 4, "maptools distance_refined band volumes")
    windows = g.storage(levels * w * h * 4, "maptools distance_refined window tops")
    columns = [g.storage(e.packed(w, h, subcells), "maptools distance_refined columns") for e in lists]
    cut = rings = ring_ends = None
    if visible:
        inner = g.storage(w * h * 4, "maptools distance_refined inner tops")
        cut = g.storage(w * h * slab * 4, "maptools distance_refined visibility cut")
        rings, ring_ends = [], []
        for b in rf.bins(sectors, 1, max_angle):
            ring = rf.horizon_rings(b, w / h, reach)
            offsets = np.concatenate([np.stack([np.mod(ox, w), np.mod(oy, h)], axis=1) for ox, oy in ring])
            # a storage buffer is never empty: one unread entry where no ring holds a cell
            rings.append(g.storage(offsets.astype(np.uint32) if len(offsets) else np.zeros((1, 2), np.uint32),
                                   "maptools distance_refined rings"))
            ends = np.cumsum([len(ox) for ox, _ in ring]).astype(np.uint32)
            ring_ends.append(g.storage(ends, "maptools distance_refined ring ends"))
    out = np.empty((len(directions) + 1, slices, h, w), np.float16)
    groups = [(s, b0) for s in range(sectors) for b0 in range(0, bands, rf.BANDS_PER_PASS)]
    passes = [(slab_, group) for slab_ in _slabs(slices, slab) for group in groups]
    windows_done = False
    for (first, count), (sector, b0) in tqdm(passes, desc="distance_refined (gpu)", unit="pass",
                                              disable=None if progress else True, leave=False):
        n = w * h * count
        group = [directions[b * sectors + sector] for b in range(b0, min(b0 + rf.BANDS_PER_PASS, bands))]
        lane = [0.0] * (4 - len(group))  # bands of the group, one per vec4 lane; unused lanes 0
        p = g.uniform("distance_refined.wgsl", {
            "width": w, "height": h, "first_slice": first, "slices": count, "subcells": subcells,
            "count": len(lists[sector].rho), "levels": levels, "bands": len(group),
            "tan_lo": [d.tan_lo for d in group] + lane, "cot_hi": [d.cot_hi for d in group] + lane,
            "inv_sin_hi": [1.0 / d.sin_hi for d in group] + lane, "cap": [reach / d.sin_hi for d in group] + lane,
            "dz": height_scale * w / slices, "grow": dist.BOX_GROW, "margin": dist.STORE_MARGIN,
            "sw": height_scale * w, "visibility": int(visible), "rings": rf.ring_count(reach),
            "horizon_step": rf.HORIZON_STEP, "reach": reach, "cot_slack": rf.COT_SLACK})
        enc = g.encoder("maptools distance_refined pass")
        if not windows_done:
            g.dispatch(enc, "distance_refined.wgsl", "window_tops", {0: p, 1: src, 2: windows}, w, h, levels)
            if visible:
                g.dispatch(enc, "distance_refined.wgsl", "inner_tops", {0: p, 1: src, 2: inner}, w, h)
            windows_done = True
        if (sector, b0) == groups[0]:  # the slab's plain values, which every pass of the slab floors at
            _plain_slab(g, enc, tops, rows, plain, w, h, first, count, slices, height_scale, subcells)
        if visible and b0 == 0:  # the sector's cut for the slab, which its band groups share
            g.dispatch(enc, "distance_refined.wgsl", "horizon",
                       {0: p, 1: inner, 2: cut, 7: rings[sector], 8: ring_ends[sector]}, w, h)
        g.dispatch(enc, "distance_refined.wgsl", "main",
                   {0: p, 1: plain, 2: vol, 3: tops, 4: windows, 5: columns[sector], 6: cut if visible else plain},
                   w, h, count)
        g.submit(enc)
        if (sector, b0) == groups[0]:
            stored = dist.round_down(g.read(plain, n).astype(np.float64), np.float16)
            out[-1, first:first + count] = stored.reshape(count, h, w)
        result = dist.round_down(g.read(vol, len(group) * n).astype(np.float64), np.float16)
        for i, b in enumerate(range(b0, b0 + len(group))):
            out[b * sectors + sector, first:first + count] = result[i * n:(i + 1) * n].reshape(count, h, w)
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
