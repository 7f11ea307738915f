"""The texture slots a technique may sample, shared by the renderer and the probe.

A technique names what it samples in ``Technique.textures``; each name is a slot here: the material's own
textures (``albedo``, ``normal``; the renderer loads them from the scene) and the height-derived ones (``depth``
and the maps maptools generates), which this module builds from a depth map. A slot knows its WGSL variable and
type (``shaders.interface`` generates the binding line: binding 2 + the slot's position in ``MAP_SLOTS``) and its
bind-group layout entry. Derived maps come from maptools' registry and disk cache (content hash + options),
never from a private copy.

A derived slot's ``check`` refuses a height map too large for the map on this adapter from its size alone (the
renderer calls it with a file's header size before loading or generating anything; ``build`` calls it too), naming
what exceeds which limit and the size of height map that fits: a scene has no map options to change. The distance
volumes choose their own options instead (``volume_plan``): the default depth slices and sub-cells where they fit,
else the most that do, said in one warning line when the map is built; refused only below the fewest slices.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import wgpu

from maptools import cone as cone_kind
from maptools import distance as distance_kind
from maptools import gpu as map_gpu
from maptools import refined as refined_kind
from maptools.cache import cached_generate
from maptools.cpu import level_sizes
from wgpuviewer.core.compute import compute_for
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import Gpu, allocating, check_texture_size, create_texture, format_bytes, mip_chain
from wgpuviewer.techniques import CONE_FILTER, CONE_MAX_RATIO, REFINED_BANDS, REFINED_MAX_ANGLE, REFINED_SECTORS

from . import autotable

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class MapSlot:
    name: str
    wgsl_type: str  # e.g. "texture_2d<f32>"
    layout: dict  # bind-group layout entry without binding/visibility
    #: Height-derived slots: (gpu, depth, height_scale, label) -> texture. None: a material texture (albedo, normal).
    build: Callable[[Gpu, np.ndarray, float, str], wgpu.GPUTexture] | None
    doc: str  # the generated binding line's comment
    #: (gpu, width, height) of the height map -> None, or a UserError when the map cannot be built from a map of
    #: that size on this adapter (module docstring); None: nothing to check (the material's own textures).
    check: Callable[[Gpu, int, int], None] | None = None
    #: Built for the material's height_scale: a tracer given another scale could step through the surface.
    scale_bound: bool = False
    #: WGSL variable (default NAME_tex); slots that are alternatives for one tracer may share it.
    variable: str = ""
    #: Built by measuring techniques on the depth map: ``build`` then takes the probe function as a fifth
    #: argument (the renderer and the probe pass ``probe.probe``; this module cannot import it).
    measured: bool = False

    @property
    def wgsl_name(self) -> str:
        return self.variable or f"{self.name}_tex"

    @property
    def derived(self) -> bool:
        return self.build is not None


#: How far a filtered depth fetch may fall outside the range of the texels it mixes (rounding of the filter
#: weights and of the format; a float16 step near 1 is 2^-11): ``depth_range`` widens the range by this much.
DEPTH_RANGE_SLACK = 2.0 ** -10


def depth_range(depth: np.ndarray, fmt: str) -> tuple[float, float]:
    """(lowest, highest) depth of ``depth`` as the depth texture holds it (``fmt``: r32float or r16float, as
    uploaded), widened by ``DEPTH_RANGE_SLACK`` and kept in [0, 1]: every depth fetch, at any mip level (the levels
    are averages), lies within it, so the layer searches march only this range (common/trace.wgsl's relief_range).
    Non-finite depths never get here: the height readers and the probe refuse them."""
    d = np.asarray(depth, np.float32)  # the upload's path: float32 first, then the texture's format
    if fmt == "r16float":
        d = d.astype(np.float16).astype(np.float32)
    lo, hi = float(d.min()), float(d.max())
    return max(0.0, lo - DEPTH_RANGE_SLACK), min(1.0, hi + DEPTH_RANGE_SLACK)


# --- size checks: what a W x H height map makes, against this adapter's limits and maptools' ---------------------

def _fits_texels(w: int, h: int, texels: int) -> str:
    """The fix for a w x h height map beyond ``texels`` texels: the largest map of its shape within."""
    scale = min(1.0, (texels / (w * h)) ** 0.5)
    return f"use a height map of at most {texels} texels (e.g. {max(1, int(w * scale))}x{max(1, int(h * scale))})"


def _check_2d(gpu: Gpu, w: int, h: int, what: str = "") -> None:
    """The map is a w x h 2D texture (a height map of up to the adapter's limit per side fits)."""
    side = gpu.device.limits["max-texture-dimension-2d"]
    check_texture_size(gpu, w, h, what or "the map", f"use a height map of at most {side} texels per side")


def _atlas_rows(sizes: list[tuple[int, int]]) -> int:
    return sum(rows for rows, _ in sizes)


def _check_atlas(gpu: Gpu, w: int, h: int, rows_of, what: str) -> None:
    """A pyramid atlas of ``rows_of(h)`` rows (the levels stacked) beyond the adapter's 2D limit: the fix names the
    tallest height map whose atlas fits."""
    side = gpu.device.limits["max-texture-dimension-2d"]
    rows = rows_of(h)
    if rows > side:
        fit = side // 2 + 1
        while fit > 1 and rows_of(fit) > side:
            fit -= 1
        raise UserError(f"the {what} atlas of a {w}x{h} height map is {rows} rows, more than this adapter's limit "
                        f"of {side} texels per side; use a height map of at most {fit} rows")


def _check_depth(gpu: Gpu, w: int, h: int) -> None:
    _check_2d(gpu, w, h)


def _check_maxmip(gpu: Gpu, w: int, h: int) -> None:
    _check_2d(gpu, w, h)
    _check_atlas(gpu, w, h, lambda rows: _atlas_rows(level_sizes(rows, 1)), "maxmip")


def _check_quadmax(gpu: Gpu, w: int, h: int) -> None:
    _check_2d(gpu, w, h)
    # quadmax_atlas: the leaves (level 1) and the levels from 2 on; a 1x1 map still gets its one leaf row
    _check_atlas(gpu, w, h, lambda rows: max(1, _atlas_rows(level_sizes(rows, 1)[1:])), "quadmax")


#: Depth slices and sub-cells per cell side of the distance volumes where they fit (maptools' defaults).
DISTANCE_SLICES = 16
DISTANCE_SUBCELLS = 4
#: Fewest depth slices a volume is reduced to; a height map that does not fit even so is refused. Fewer slices stay
#: exact but cost fetches (docs/maps.md, "Large height maps"): a slice spans S*W/Dz texels of depth.
MIN_SLICES = 4
#: A refined map of at most this many slices saves no fetches over the plain map at 16 (measured at 1K and 2K:
#: docs/maps.md, "Large height maps"): where that is all that fits, the one line says so.
REFINED_PAYS_SLICES = DISTANCE_SLICES // 2


@dataclass(frozen=True)
class VolumePlan:
    """How a distance slot's volume is built from a W x H height map on this adapter: its depth slices and
    sub-cells, the largest (up to the defaults) that fit the adapter's and maptools' limits, and what made them
    smaller (``reduced``: one clause per reduction; empty: the defaults)."""

    kind: str
    width: int
    height: int
    slices: int
    subcells: int
    reduced: tuple[str, ...] = ()
    #: A better choice where the user is, or "" (a refined map with few slices: the plain one at more slices).
    advice: str = ""

    @property
    def volumes(self) -> int:
        return REFINED_SECTORS * REFINED_BANDS + 1 if self.kind == "distance_refined" else 1

    @property
    def nbytes(self) -> int:
        """Bytes of the texture: float16 volumes (``uploaded_volume``)."""
        return self.width * self.height * self.slices * self.volumes * 2

    def note(self, label: str) -> str:
        """The one line saying what was chosen and why (for a reduced plan)."""
        return (f"{label}: a {self.width}x{self.height} height map gets {'; '.join(self.reduced)}; "
                f"{format_bytes(self.nbytes)}; the tracer stays exact, at more fetches per ray"
                f"{'; ' + self.advice if self.advice else ''} (docs/maps.md)")


def volume_plan(gpu: Gpu, kind: str, w: int, h: int) -> VolumePlan:
    """The settings a w x h height map's ``kind`` volume (distance, distance_refined) is built with here: the
    defaults, else the most slices (down to MIN_SLICES) and sub-cells within the adapter's 3D texture limit,
    maptools' volume limits and the adapter's storage buffers (the bake binds the sub-cell tops whole); a
    UserError naming what the scene can change when even the fewest do not fit."""
    refined = kind == "distance_refined"
    volumes = REFINED_SECTORS * REFINED_BANDS + 1 if refined else 1
    side = gpu.device.limits["max-texture-dimension-3d"]
    if max(w, h) > side:
        raise UserError(f"{kind}: a volume of {w}x{h} texels per slice exceeds this adapter's 3D limit of {side} "
                        f"texels per side; use a height map of at most {side} texels per side")

    def layers(n: int) -> str:
        return f"{volumes} x {n} slices stack {volumes * n} layers, more than this adapter's 3D limit of {side} texels"

    def values(limit: int, unit: str, per_volume: int) -> Callable[[int], str]:
        held = f"{per_volume} volumes of {w}x{h}x{{}} hold" if per_volume > 1 else f"a {w}x{h}x{{}} volume holds"
        return lambda n: (f"{held.format(n)} {per_volume * n * w * h} values, more than maptools' limit of {limit} "
                          f"({unit})")

    # (most slices within the limit, what n slices exceed, the fix when MIN_SLICES exceed it)
    limits = [(side // volumes, layers, "use the technique distance")]
    if refined:
        limits.append((refined_kind.MAX_VALUES // (w * h * volumes),
                       values(refined_kind.MAX_VALUES, "float16", volumes),
                       _fits_texels(w, h, refined_kind.MAX_VALUES // (volumes * MIN_SLICES))
                       + ", or the technique distance"))
    limits.append((distance_kind.MAX_VOXELS // (w * h), values(distance_kind.MAX_VOXELS, "float32", 1),
                   _fits_texels(w, h, distance_kind.MAX_VOXELS // MIN_SLICES)))
    for most, exceeded, fix in limits:
        if most < MIN_SLICES:
            raise UserError(f"{kind}: even at {MIN_SLICES} depth slices (the fewest it is built with) "
                            f"{exceeded(MIN_SLICES)}; {fix}")
    slices = min(DISTANCE_SLICES, *(most for most, _, _ in limits))
    reduced = [f"{slices} depth slices instead of {DISTANCE_SLICES} ({exceeded(DISTANCE_SLICES)})"
               for most, exceeded, _ in limits if most == slices < DISTANCE_SLICES][:1]
    max_buffer = compute_for(gpu).max_buffer
    lanes = refined_kind.BANDS_PER_PASS if refined else 0
    subcells = map_gpu.fitting_subcells(w, h, max_buffer, lanes, most=DISTANCE_SUBCELLS)
    if subcells is None:
        raise UserError(f"{kind}: baking a {w}x{h} volume needs storage buffers of "
                        f"{format_bytes(max(map_gpu.bake_buffers(w, h, 1, lanes)))}, more than the "
                        f"{format_bytes(max_buffer)} this adapter binds; use a smaller height map")
    if subcells < DISTANCE_SUBCELLS:
        need = max(map_gpu.bake_buffers(w, h, DISTANCE_SUBCELLS, lanes))
        reduced.append(f"{subcells}x{subcells} sub-cells per cell instead of {DISTANCE_SUBCELLS}x"
                       f"{DISTANCE_SUBCELLS} (whose bake needs a {format_bytes(need)} buffer, more than the "
                       f"{format_bytes(max_buffer)} this adapter binds)")
    advice = ""
    if refined and slices <= REFINED_PAYS_SLICES:
        plain = volume_plan(gpu, "distance", w, h)
        if plain.slices > slices:
            advice = (f"the technique distance ({plain.slices} slices here, {format_bytes(plain.nbytes)}) takes about "
                      "as many fetches or fewer")
    return VolumePlan(kind, w, h, slices, subcells, tuple(reduced), advice)


def _check_distance(gpu: Gpu, w: int, h: int) -> None:
    volume_plan(gpu, "distance", w, h)


def _check_distance_refined(gpu: Gpu, w: int, h: int) -> None:
    volume_plan(gpu, "distance_refined", w, h)


def _check_cone(gpu: Gpu, w: int, h: int) -> None:
    _check_2d(gpu, w, h)
    rings = cone_kind.ring_count(CONE_MAX_RATIO, w, h)
    if rings > cone_kind.MAX_RINGS:  # maptools' own message names its --max-ratio, which a scene does not have
        raise UserError(f"cone: a {w}x{h} height map needs {rings} search rings, more than {cone_kind.MAX_RINGS}; "
                        "use a less elongated height map")


def _map_backend(gpu: Gpu, w: int, h: int) -> str:
    """maptools' backend for a 2D map kind of a w x h height map: its GPU kernel where the map's storage buffers
    (4 bytes a texel) fit the adapter's limit, else the CPU reference (a scene cannot pick a backend)."""
    return "auto" if w * h * 4 <= compute_for(gpu).max_buffer else "cpu"


def _size(depth: np.ndarray) -> tuple[int, int]:
    h, w = depth.shape[:2]
    return w, h


# --- builders ------------------------------------------------------------------------------------------------------

def _depth(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    _check_depth(gpu, *_size(depth))
    return create_texture(gpu, mip_chain(depth), gpu.depth_format, label)


def _complexity(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    _check_depth(gpu, *_size(depth))
    # Relief textures tile, so the Sobel and the dilation wrap around the borders.
    levels = cached_generate("complexity", 1.0 - depth, backend=_map_backend(gpu, *_size(depth)), border="repeat")
    # 8-bit levels k/255 as a filterable float texture (r8unorm has no upload path in gpu.to_texel_data).
    return create_texture(gpu, [levels.astype(np.float32) / 255.0], gpu.depth_format, label)


def cell_max_height(depth: np.ndarray) -> np.ndarray:
    """Height bound of each bilinear cell: max of the cell's four corner texels (wrap), float32 (H, W).

    Cell (i, j) lies between the texel centres i, i+1 and j, j+1 (texel coordinates x = u*W - 0.5); the bilinear
    patch over it never rises above its highest corner, so a max pyramid over these values bounds the sampled
    surface (a pyramid over the texels alone does not: a patch reaches into the neighbouring texel's cell).
    """
    # 1 - depth in the input's precision, then float32 (rounding commutes with the maxima): few temporaries.
    h = (1.0 - np.asarray(depth)).astype(np.float32, copy=False)
    cell = np.maximum(h, np.roll(h, -1, axis=1))
    np.maximum(cell, np.roll(cell, -1, axis=0), out=cell)  # the rows below: their own max of two columns
    return np.clip(cell, 0.0, 1.0, out=cell)


def maxmip_atlas(levels: list[np.ndarray]) -> np.ndarray:
    """maptools' maxmip levels (ceil-halving) stacked into one (sum of heights, W) float32 image: level m at
    rows [sum of earlier heights, + h_m), columns [0, w_m). common/maxmip_walk.wgsl computes the same row offsets."""
    width = levels[0].shape[1]
    atlas = np.zeros((sum(level.shape[0] for level in levels), width), np.float32)
    row = 0
    for level in levels:
        atlas[row:row + level.shape[0], :level.shape[1]] = level
        row += level.shape[0]
    return atlas


def _maxmip(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    _check_maxmip(gpu, *_size(depth))
    levels = cached_generate("maxmip", cell_max_height(depth), backend=_map_backend(gpu, *_size(depth)))
    return create_texture(gpu, [maxmip_atlas(levels)], "r32float", label)


#: Quantisation of the quadmax leaves: 14-bit depths q = floor(D * 16383), 9 of them in one rgba32uint texel.
LEAF_BITS = 14
LEAF_SCALE = (1 << LEAF_BITS) - 1


def pack_leaves(depth: np.ndarray) -> np.ndarray:
    """One rgba32uint texel (uint32 (ceil(H/2), ceil(W/2), 4)) per 2x2-cell block: the 9 texel depths D of texels
    (2i + a, 2j + b), a, b in 0..2 (wrap), as 14-bit q = floor(D * 16383 - 2^-8) (so q / 16383 <= D even after
    float32 rounding: the leaves' surface is never below the true one), value k = 3 b + a at bits [14 k, 14 k + 14)
    of the 128-bit little-endian word sequence (quadmax.wgsl's leaf_depth)."""
    d = np.asarray(depth, np.float64)
    h, w = d.shape
    bh, bw = (h + 1) // 2, (w + 1) // 2
    q = np.clip(np.floor(d * LEAF_SCALE - 2.0 ** -8), 0, LEAF_SCALE).astype(np.uint64)
    rows, cols = np.arange(bh) * 2, np.arange(bw) * 2
    words = np.zeros((bh, bw, 4), np.uint64)
    for k in range(9):
        b, a = divmod(k, 3)
        value = q[np.ix_((rows + b) % h, (cols + a) % w)]
        bit = LEAF_BITS * k
        word, shift = divmod(bit, 32)
        words[:, :, word] |= (value << np.uint64(shift)) & np.uint64(0xFFFFFFFF)
        if shift + LEAF_BITS > 32:
            words[:, :, word + 1] |= value >> np.uint64(32 - shift)
    return words.astype(np.uint32)


def quadmax_atlas(depth: np.ndarray, levels: list[np.ndarray]) -> np.ndarray:
    """The quadmax tracer's atlas, uint32 (rows, ceil(W/2), 4) for rgba32uint: node level 1 (2x2 cells) at rows
    [0, h_1) holds the packed leaves (``pack_leaves``); level m >= 2 (sizes ceil-halving down to 1x1) at rows
    [h_1 + ... + h_{m-1}, + h_m) holds per node P the maxima (float32 bits) of its four children at level m - 1,
    (2P + (0,0), (1,0), (0,1), (1,1)) in x, y, z, w: one fetch tells which children a ray can skip. ``levels``:
    maptools' maxmip of ``cell_max_height(depth)`` (level m bounds the cells [i 2^m, (i + 1) 2^m) from above).
    A 1x1 map still gets level 1 (one leaf)."""
    leaves = pack_leaves(depth)
    levels = list(levels) + [levels[-1]] * (len(levels) < 2)  # 1x1: level 1 = level 0
    parts = [leaves]
    for m in range(2, len(levels)):
        child = levels[m - 1]
        ph, pw = levels[m].shape
        quad = np.zeros((ph, pw, 4), np.float32)
        for c, (dy, dx) in enumerate(((0, 0), (0, 1), (1, 0), (1, 1))):
            part = child[dy::2, dx::2]
            quad[:part.shape[0], :part.shape[1], c] = part
        parts.append(quad.view(np.uint32))
    atlas = np.zeros((sum(p.shape[0] for p in parts), leaves.shape[1], 4), np.uint32)
    row = 0
    for part in parts:
        atlas[row:row + part.shape[0], :part.shape[1]] = part
        row += part.shape[0]
    return atlas


def _uint_texture(gpu: Gpu, data: np.ndarray, label: str) -> wgpu.GPUTexture:
    h, w = data.shape[:2]
    _check_2d(gpu, w, h, label)
    with allocating(gpu, label, w * h * 16, "use a smaller height map"):
        texture = gpu.device.create_texture(label=label, size=(w, h, 1), format="rgba32uint",
                                            usage=wgpu.TextureUsage.TEXTURE_BINDING | wgpu.TextureUsage.COPY_DST)
    data = np.ascontiguousarray(data, np.uint32)
    gpu.device.queue.write_texture({"texture": texture, "mip_level": 0, "origin": (0, 0, 0)}, data,
                                   {"offset": 0, "bytes_per_row": w * 16, "rows_per_image": h}, (w, h, 1))
    return texture


def _quadmax(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    _check_quadmax(gpu, *_size(depth))
    levels = cached_generate("maxmip", cell_max_height(depth), backend=_map_backend(gpu, *_size(depth)))
    return _uint_texture(gpu, quadmax_atlas(depth, levels), label)


def _auto_table(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str, probe) -> wgpu.GPUTexture:
    _check_quadmax(gpu, *_size(depth))  # auto's candidates trace the depth and the quadmax atlas
    return autotable.table_texture(gpu, autotable.measure(depth, height_scale, probe), label)


def uploaded_volume(volume: np.ndarray) -> np.ndarray:
    """A distance volume as the renderer uploads it: float16, every value rounded down (a step never grows, so
    the map stays safe). For the plain map this halves its memory; the refined-distance study measures the cost
    within +-0.2 % of the fetches (docs/maps.md). The refined kind is float16 already."""
    if volume.dtype == np.float16:
        return volume
    return distance_kind.round_down(np.asarray(volume, np.float64), np.float16)


def _volume_texture(gpu: Gpu, volume: np.ndarray, label: str) -> wgpu.GPUTexture:
    """A (Dz, H, W) volume, or (V, Dz, H, W) volumes stacked along the depth (volume v at depths [v Dz, (v + 1) Dz)),
    as an r16float 3D texture (``uploaded_volume``); converted and uploaded one depth layer at a time (no copy of
    the whole volume)."""
    h, w = volume.shape[-2:]
    depth = volume.size // (w * h)
    with allocating(gpu, label, w * h * depth * 2, "use a smaller height map"):
        texture = gpu.device.create_texture(
            label=label, size=(w, h, depth), dimension="3d", format="r16float",
            usage=wgpu.TextureUsage.TEXTURE_BINDING | wgpu.TextureUsage.COPY_DST,
        )
    layers = volume.reshape(depth, h, w)
    for z in range(depth):
        gpu.device.queue.write_texture(
            {"texture": texture, "mip_level": 0, "origin": (0, 0, z)},
            np.ascontiguousarray(uploaded_volume(layers[z])),
            {"offset": 0, "bytes_per_row": w * 2, "rows_per_image": h}, (w, h, 1),
        )
    return texture


def _planned(gpu: Gpu, kind: str, depth: np.ndarray, label: str) -> VolumePlan:
    """The volume plan of a height map, its reductions said in one warning line."""
    plan = volume_plan(gpu, kind, *_size(depth))
    if plan.reduced:
        log.warning(plan.note(label))
    return plan


def _distance(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    plan = _planned(gpu, "distance", depth, label)
    volume = cached_generate("distance", 1.0 - depth, backend="auto", slices=plan.slices, subcells=plan.subcells,
                             height_scale=height_scale)
    return _volume_texture(gpu, volume, label)


def _distance_refined(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    plan = _planned(gpu, "distance_refined", depth, label)
    volumes = cached_generate("distance_refined", 1.0 - depth, backend="auto", slices=plan.slices,
                              subcells=plan.subcells, height_scale=height_scale, max_angle=REFINED_MAX_ANGLE,
                              sectors=REFINED_SECTORS, bands=REFINED_BANDS)
    return _volume_texture(gpu, volumes, label)


def footprint_min_depth(depth: np.ndarray, fmt: str) -> np.ndarray:
    """Per texel q, a lower bound of the bilinear depth anywhere in q's footprint [i, i+1] x [j, j+1] (u * W, v * H):
    the minimum of the 3x3 texels around q (wrap), the texels that footprint's bilinear surface mixes, in the depth
    texture's precision (``fmt``: r32float or r16float, as uploaded), float32 (H, W)."""
    d = np.asarray(depth, np.float32)  # the upload's path: float32 first, then the texture's format
    if fmt == "r16float":
        d = d.astype(np.float16).astype(np.float32)
    out = np.minimum(d, np.minimum(np.roll(d, 1, axis=1), np.roll(d, -1, axis=1)))
    return np.minimum(out, np.minimum(np.roll(out, 1, axis=0), np.roll(out, -1, axis=0)))


def _cone(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    # The ratios do not depend on height_scale (texels of u per unit t); cone.wgsl reads (ratio, footprint min
    # depth) with textureLoad (nearest texel), the lookup a filter="nearest" map is built for: one fetch per cone
    # step, which proves the ray free where it is above the footprint's lowest depth.
    _check_cone(gpu, *_size(depth))
    ratios = cached_generate("cone", 1.0 - depth, backend=_map_backend(gpu, *_size(depth)), max_ratio=CONE_MAX_RATIO,
                             filter=CONE_FILTER)
    packed = np.stack([np.asarray(ratios, np.float32), footprint_min_depth(depth, gpu.depth_format)], axis=-1)
    return create_texture(gpu, [packed], "rg32float", label)


_FILTERABLE_2D = {"texture": {"sample_type": "float", "view_dimension": "2d"}}
_UNFILTERABLE_2D = {"texture": {"sample_type": "unfilterable-float", "view_dimension": "2d"}}
_VOLUME = {"texture": {"sample_type": "unfilterable-float", "view_dimension": "3d"}}
_UINT_2D = {"texture": {"sample_type": "uint", "view_dimension": "2d"}}
_2D, _3D = "texture_2d<f32>", "texture_3d<f32>"

MAP_SLOTS: dict[str, MapSlot] = {
    slot.name: slot
    for slot in (
        MapSlot("albedo", _2D, _FILTERABLE_2D, None, "linear RGB albedo (rgba16float), mip chain"),
        MapSlot("normal", _2D, _FILTERABLE_2D, None, "tangent-space normals as n * 0.5 + 0.5 (rgba8unorm)"),
        MapSlot("depth", _2D, _FILTERABLE_2D, _depth, "D = 1 - height, mip chain (r32float, or r16float)",
                check=_check_depth),
        MapSlot("complexity", _2D, _FILTERABLE_2D, _complexity, "the thesis' complexity map, levels k/255",
                check=_check_depth),
        MapSlot("maxmip", _2D, _UNFILTERABLE_2D, _maxmip,
                "max pyramid atlas (r32float): level m at rows [row_m, row_m + h_m), textureLoad", check=_check_maxmip),
        # distance.wgsl reads whichever of the two distance volumes its technique needs, as distance_tex.
        MapSlot("distance", _3D, _VOLUME, _distance, "distance volume (W, H, slices), r16float rounded down, "
                "textureLoad",
                check=_check_distance, scale_bound=True),
        MapSlot("distance_refined", _3D, _VOLUME, _distance_refined,
                "direction-binned refined volumes and the plain one, stacked along the depth (r16float), textureLoad",
                check=_check_distance_refined, scale_bound=True, variable="distance_tex"),
        MapSlot("cone", _2D, _UNFILTERABLE_2D, _cone,
                "relaxed cone ratio (texels of u per unit t) and footprint min depth (rg32float), textureLoad",
                check=_check_cone),
        MapSlot("quadmax", "texture_2d<u32>", _UINT_2D, _quadmax,
                "max quadtree atlas (rgba32uint): packed 14-bit leaves (level 1), children's maxima (levels >= 2)",
                check=_check_quadmax),
        MapSlot("auto_table", _2D, _UNFILTERABLE_2D, _auto_table,
                "auto's choices (rgba32float, bins x budget levels): candidate, method, parameter, error",
                check=_check_quadmax, scale_bound=True, measured=True),
    )
}

#: @group(1) bindings: the TraceParams uniform, the material sampler, then the texture slots.
PARAMS_BINDING, SAMPLER_BINDING, FIRST_SLOT_BINDING = 0, 1, 2


def binding(name: str) -> int:
    """@group(1) @binding(N) of a texture slot."""
    return FIRST_SLOT_BINDING + list(MAP_SLOTS).index(name)


def layout_entries(names, visibility) -> list[dict]:
    """Bind-group layout entries for the texture slots ``names``."""
    return [{"binding": binding(n), "visibility": visibility, **MAP_SLOTS[n].layout} for n in names]


def height_scale_adjustable(textures) -> bool:
    """Whether a technique sampling ``textures`` may trace at another height scale than its maps were built for."""
    return not any(MAP_SLOTS[t].scale_bound for t in textures)
