"""The distance_refined kind's texture slot ``distance_refined``: its direction-binned volumes and the plain one,
stacked along the depth of one r16float 3D texture, with the volume plan a height map gets on this adapter
(``maptools/volume/slot.py``); and the bins the renderer builds it with, which the tracer reads too.

May import: ``wgpuviewer.core``, numpy, wgpu, maptools' shared modules and this folder.
"""

from __future__ import annotations

import numpy as np
import wgpu

from maptools.cache import cached_generate
from maptools.volume.slot import Binned, VolumePlan, planned, volume_plan, volume_texture
from wgpuviewer.core.gpu import Gpu
from wgpuviewer.core.slots import TEXTURE_3D, VOLUME, MapSlot

from . import cpu
from .bins import BANDS_PER_PASS

#: The refined distance map's direction bins (the slot builds it with these distance_refined options; the
#: tracer picks a ray's volume from the same numbers, see distance.wgsl): azimuth sectors, polar bands (edges of
#: equal cosine ratio) and the binned cone's half-angle; steeper rays read the plain volume stored last. 85 rather
#: than 80 degrees: a benchmark frame centred at 80 degrees spans 79.3-80.7, and with an 80-degree cone its steeper
#: half read the plain volume (wall: -8 % instead of -42 % fetches); 85 costs no memory (measured: docs/maps.md).
REFINED_SECTORS = 4
REFINED_BANDS = 8
REFINED_MAX_ANGLE = 85.0



def binned() -> Binned:
    """What the bins add to the volume plan: their volumes and the plain one, maptools' float16 limit (read when
    planned), the bake's lanes."""
    return Binned(REFINED_SECTORS * REFINED_BANDS + 1, cpu.MAX_VALUES, BANDS_PER_PASS)


def plan(gpu: Gpu, w: int, h: int) -> VolumePlan:
    """The settings a w x h height map's refined volumes are built with here (``volume_plan``)."""
    return volume_plan(gpu, "distance_refined", w, h, binned())


def check_distance_refined(gpu: Gpu, w: int, h: int) -> None:
    plan(gpu, w, h)


def build_distance_refined(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    chosen = planned(gpu, "distance_refined", depth, label, binned())
    volumes = cached_generate("distance_refined", 1.0 - depth, backend="auto", slices=chosen.slices,
                              subcells=chosen.subcells, height_scale=height_scale, max_angle=REFINED_MAX_ANGLE,
                              sectors=REFINED_SECTORS, bands=REFINED_BANDS)
    return volume_texture(gpu, volumes, label)


SLOTS = (
    MapSlot("distance_refined", TEXTURE_3D, VOLUME, build_distance_refined,
            "direction-binned refined volumes and the plain one, stacked along the depth (r16float), textureLoad",
            check=check_distance_refined, scale_bound=True, variable="distance_tex", order=50),
)
