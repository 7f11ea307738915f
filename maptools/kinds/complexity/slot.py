"""The complexity kind's texture slot ``complexity``: the thesis' map with wrapping borders, levels k/255.

May import: ``wgpuviewer.core``, numpy, wgpu, maptools' shared modules and this folder.
"""

from __future__ import annotations

import numpy as np
import wgpu

from maptools.cache import cached_generate
from wgpuviewer.core.gpu import Gpu, create_texture
from wgpuviewer.core.slots import FILTERABLE_2D, TEXTURE_2D, MapSlot, check_2d, map_backend, size_of


def check_complexity(gpu: Gpu, w: int, h: int) -> None:
    check_2d(gpu, w, h)


def build_complexity(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    check_complexity(gpu, *size_of(depth))
    # Relief textures tile, so the Sobel and the dilation wrap around the borders.
    levels = cached_generate("complexity", 1.0 - depth, backend=map_backend(gpu, *size_of(depth)), border="repeat")
    # 8-bit levels k/255 as a filterable float texture (r8unorm has no upload path in gpu.to_texel_data).
    return create_texture(gpu, [levels.astype(np.float32) / 255.0], gpu.depth_format, label)


SLOTS = (
    MapSlot("complexity", TEXTURE_2D, FILTERABLE_2D, build_complexity, "the thesis' complexity map, levels k/255",
            check=check_complexity, order=20),
)
