"""The maxmip kind's texture slots: ``maxmip`` (the pyramid's levels stacked into one r32float atlas) and ``quadmax``
(the max quadtree atlas: packed 14-bit leaves, then per node its four children's maxima, from the same levels). Both
pyramids are built over the bilinear cells' corner maxima (``cell_max_height``), which bound the sampled surface.

May import: ``wgpuviewer.core``, numpy, wgpu, maptools' shared modules and this folder.
"""

from __future__ import annotations

import numpy as np
import wgpu

from maptools.cache import cached_generate
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import Gpu, create_texture
from wgpuviewer.core.slots import (
    TEXTURE_2D,
    UINT_2D,
    UINT_TEXTURE_2D,
    UNFILTERABLE_2D,
    MapSlot,
    check_2d,
    map_backend,
    size_of,
    uint_texture,
)

from .cpu import level_sizes


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


def check_maxmip(gpu: Gpu, w: int, h: int) -> None:
    check_2d(gpu, w, h)
    _check_atlas(gpu, w, h, lambda rows: _atlas_rows(level_sizes(rows, 1)), "maxmip")


def check_quadmax(gpu: Gpu, w: int, h: int) -> None:
    check_2d(gpu, w, h)
    # quadmax_atlas: the leaves (level 1) and the levels from 2 on; a 1x1 map still gets its one leaf row
    _check_atlas(gpu, w, h, lambda rows: max(1, _atlas_rows(level_sizes(rows, 1)[1:])), "quadmax")


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
    return stacked(levels, np.float32)


def stacked(parts: list[np.ndarray], dtype) -> np.ndarray:
    """``parts`` stacked top to bottom into one array as wide as the first, each at the left edge (zeros beside)."""
    atlas = np.zeros((sum(part.shape[0] for part in parts), *parts[0].shape[1:]), dtype)
    row = 0
    for part in parts:
        atlas[row:row + part.shape[0], :part.shape[1]] = part
        row += part.shape[0]
    return atlas


def build_maxmip(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    check_maxmip(gpu, *size_of(depth))
    levels = cached_generate("maxmip", cell_max_height(depth), backend=map_backend(gpu, *size_of(depth)))
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
    return stacked(parts, np.uint32)


def build_quadmax(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    check_quadmax(gpu, *size_of(depth))
    levels = cached_generate("maxmip", cell_max_height(depth), backend=map_backend(gpu, *size_of(depth)))
    return uint_texture(gpu, quadmax_atlas(depth, levels), label)


SLOTS = (
    MapSlot("maxmip", TEXTURE_2D, UNFILTERABLE_2D, build_maxmip,
            "max pyramid atlas (r32float): level m at rows [row_m, row_m + h_m), textureLoad", check=check_maxmip,
            order=30),
    MapSlot("quadmax", UINT_TEXTURE_2D, UINT_2D, build_quadmax,
            "max quadtree atlas (rgba32uint): packed 14-bit leaves (level 1), children's maxima (levels >= 2)",
            check=check_quadmax, order=70),
)
