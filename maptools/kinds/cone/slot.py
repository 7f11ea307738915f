"""The cone kind's texture slot ``cone``: the relaxed cone ratios and each texel's footprint min depth (rg32float),
and the map options the renderer builds it with (the cone tracer reads the same numbers).

May import: ``wgpuviewer.core``, numpy, wgpu, maptools' shared modules and this folder.
"""

from __future__ import annotations

import numpy as np
import wgpu

from maptools.cache import cached_generate
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import Gpu, create_texture
from wgpuviewer.core.slots import TEXTURE_2D, UNFILTERABLE_2D, MapSlot, check_2d, map_backend, size_of

from .cpu import MAX_RINGS, ring_count

#: The relaxed cone map the cone tracer reads (this slot builds it): its widest stored cone (texels of u per unit t;
#: the build costs O(max_ratio^2) per texel) and its lookup (cone.wgsl reads the nearest texel).
CONE_MAX_RATIO = 32.0
CONE_FILTER = "nearest"


def check_cone(gpu: Gpu, w: int, h: int) -> None:
    check_2d(gpu, w, h)
    rings = ring_count(CONE_MAX_RATIO, w, h)
    if rings > MAX_RINGS:  # maptools' own message names its --max-ratio, which a scene does not have
        raise UserError(f"cone: a {w}x{h} height map needs {rings} search rings, more than {MAX_RINGS}; "
                        "use a less elongated height map")


def footprint_min_depth(depth: np.ndarray, fmt: str) -> np.ndarray:
    """Per texel q, a lower bound of the bilinear depth anywhere in q's footprint [i, i+1] x [j, j+1] (u * W, v * H):
    the minimum of the 3x3 texels around q (wrap), the texels that footprint's bilinear surface mixes, in the depth
    texture's precision (``fmt``: r32float or r16float, as uploaded), float32 (H, W)."""
    d = np.asarray(depth, np.float32)  # the upload's path: float32 first, then the texture's format
    if fmt == "r16float":
        d = d.astype(np.float16).astype(np.float32)
    out = np.minimum(d, np.minimum(np.roll(d, 1, axis=1), np.roll(d, -1, axis=1)))
    return np.minimum(out, np.minimum(np.roll(out, 1, axis=0), np.roll(out, -1, axis=0)))


def build_cone(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    # The ratios do not depend on height_scale (texels of u per unit t); cone.wgsl reads (ratio, footprint min
    # depth) with textureLoad (nearest texel), the lookup a filter="nearest" map is built for: one fetch per cone
    # step, which proves the ray free where it is above the footprint's lowest depth.
    check_cone(gpu, *size_of(depth))
    ratios = cached_generate("cone", 1.0 - depth, backend=map_backend(gpu, *size_of(depth)), max_ratio=CONE_MAX_RATIO,
                             filter=CONE_FILTER)
    packed = np.stack([np.asarray(ratios, np.float32), footprint_min_depth(depth, gpu.depth_format)], axis=-1)
    return create_texture(gpu, [packed], "rg32float", label)


SLOTS = (
    MapSlot("cone", TEXTURE_2D, UNFILTERABLE_2D, build_cone,
            "relaxed cone ratio (texels of u per unit t) and footprint min depth (rg32float), textureLoad",
            check=check_cone, order=60),
)
