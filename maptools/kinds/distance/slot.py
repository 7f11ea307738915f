"""The distance kind's texture slot ``distance``: the plain volume as an r16float 3D texture, with the volume plan a
height map gets on this adapter (``maptools/volume/slot.py``).

May import: ``wgpuviewer.core``, numpy, wgpu, maptools' shared modules and this folder.
"""

from __future__ import annotations

import numpy as np
import wgpu

from maptools.cache import cached_generate
from maptools.volume.slot import VolumePlan, planned, volume_plan, volume_texture
from wgpuviewer.core.gpu import Gpu
from wgpuviewer.core.slots import TEXTURE_3D, VOLUME, MapSlot


def plan(gpu: Gpu, w: int, h: int) -> VolumePlan:
    """The settings a w x h height map's distance volume is built with here (``volume_plan``)."""
    return volume_plan(gpu, "distance", w, h)


def check_distance(gpu: Gpu, w: int, h: int) -> None:
    plan(gpu, w, h)


def build_distance(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    chosen = planned(gpu, "distance", depth, label)
    volume = cached_generate("distance", 1.0 - depth, backend="auto", slices=chosen.slices, subcells=chosen.subcells,
                             height_scale=height_scale)
    return volume_texture(gpu, volume, label)


SLOTS = (
    # the distance tracer reads whichever of the two distance volumes its technique needs, as distance_tex.
    MapSlot("distance", TEXTURE_3D, VOLUME, build_distance,
            "distance volume (W, H, slices), r16float rounded down, textureLoad",
            check=check_distance, scale_bound=True, order=40),
)
