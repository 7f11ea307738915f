"""auto's own texture slot, ``auto_table``: its choices per view-angle bin and error budget, measured on the
material's depth map by the probe (``autotable``) and uploaded as a small texture.

May import: ``wgpuviewer.core``, ``maptools`` (the quadmax atlas's size check: auto's candidates trace it) and its
folder's ``autotable``.
"""

from __future__ import annotations

import numpy as np
import wgpu

from maptools.kinds.maxmip.slot import check_quadmax
from wgpuviewer.core.gpu import Gpu
from wgpuviewer.core.slots import TEXTURE_2D, UNFILTERABLE_2D, MapSlot, size_of

from . import autotable


def build_auto_table(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    check_quadmax(gpu, *size_of(depth))  # auto's candidates trace the depth and the quadmax atlas
    return autotable.table_texture(gpu, autotable.measure(depth, height_scale), label)


AUTO_TABLE_SLOT = MapSlot(
    "auto_table", TEXTURE_2D, UNFILTERABLE_2D, build_auto_table,
    "auto's choices (rgba32float, bins x budget levels): candidate, method, parameter, error",
    check=check_quadmax, scale_bound=True, order=80,
)
