"""Height-derived GPU resources a technique samples, shared by the renderer and the probe.

A technique names what it samples in ``Technique.textures``; for every height-derived entry
(``depth`` and the maps maptools generates) this module knows its WGSL binding (declared in
``prelude.wgsl``), its bind-group layout entry and how to build it from a depth map. Derived maps
come from maptools' registry and disk cache (content hash + options), never from a private copy.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import wgpu
from maptools.cache import cached_generate

from .gpu import Gpu, create_texture, mip_chain


@dataclass(frozen=True)
class MapSlot:
    name: str
    binding: int  # @group(1) @binding(N) in prelude.wgsl
    layout: dict  # bind-group layout entry without binding/visibility
    build: Callable[[Gpu, np.ndarray, float, str], wgpu.GPUTexture]  # (gpu, depth, height_scale, label)


def _depth(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    return create_texture(gpu, mip_chain(depth), gpu.depth_format, label)


def _complexity(gpu: Gpu, depth: np.ndarray, height_scale: float, label: str) -> wgpu.GPUTexture:
    # Relief textures tile, so the Sobel and the dilation wrap around the borders.
    levels = cached_generate("complexity", 1.0 - depth, backend="auto", border="repeat")
    return create_texture(gpu, [levels.astype(np.float32) / 255.0], "r8unorm", label)


_FILTERABLE_2D = {"texture": {"sample_type": "float", "view_dimension": "2d"}}

MAP_SLOTS: dict[str, MapSlot] = {
    slot.name: slot
    for slot in (
        MapSlot("depth", 4, _FILTERABLE_2D, _depth),
        MapSlot("complexity", 5, _FILTERABLE_2D, _complexity),
    )
}


def layout_entries(names, visibility) -> list[dict]:
    """Bind-group layout entries for the height-derived textures among ``names``."""
    return [
        {"binding": MAP_SLOTS[n].binding, "visibility": visibility, **MAP_SLOTS[n].layout}
        for n in names if n in MAP_SLOTS
    ]
