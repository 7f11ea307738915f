"""The texture-slot type and the small texture helpers the slots share.

A slot is one texture a technique may sample (``Technique.textures`` names them): its WGSL type and variable, its
bind-group layout entry and, for a map derived from the depth map, its build function and size check. The slots
live where their map does (a map kind's ``slot.py`` in ``maptools/kinds/KIND/``, a technique's own in its folder,
the material's in ``relief.maps``); ``relief.maps.MAP_SLOTS`` is the one table of them.

May import: nothing of the project outside ``wgpuviewer.core``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import wgpu

from .gpu import Gpu, allocating, check_texture_size


@dataclass(frozen=True)
class MapSlot:
    name: str
    wgsl_type: str  # e.g. "texture_2d<f32>"
    layout: dict  # bind-group layout entry without binding/visibility
    #: Height-derived slots: (gpu, depth, height_scale, label) -> texture. None: a material texture (albedo, normal).
    build: Callable[[Gpu, np.ndarray, float, str], wgpu.GPUTexture] | None
    doc: str  # the generated binding line's comment
    #: (gpu, width, height) of the height map -> None, or a UserError when the map cannot be built from a map of
    #: that size on this adapter; None: nothing to check (the material's own textures). The renderer calls it with a
    #: file's header size before loading or generating anything; ``build`` calls it too.
    check: Callable[[Gpu, int, int], None] | None = None
    #: Built for the material's height_scale: a tracer given another scale could step through the surface.
    scale_bound: bool = False
    #: WGSL variable (default NAME_tex); slots that are alternatives for one tracer may share it.
    variable: str = ""
    #: Its place in the binding order (``relief.maps.MAP_SLOTS``): by this number, then by name.
    order: int = 0

    @property
    def wgsl_name(self) -> str:
        return self.variable or f"{self.name}_tex"

    @property
    def derived(self) -> bool:
        return self.build is not None


# --- layout entries and WGSL types ------------------------------------------------------------------------------

FILTERABLE_2D = {"texture": {"sample_type": "float", "view_dimension": "2d"}}
UNFILTERABLE_2D = {"texture": {"sample_type": "unfilterable-float", "view_dimension": "2d"}}
VOLUME = {"texture": {"sample_type": "unfilterable-float", "view_dimension": "3d"}}
UINT_2D = {"texture": {"sample_type": "uint", "view_dimension": "2d"}}
TEXTURE_2D, TEXTURE_3D, UINT_TEXTURE_2D = "texture_2d<f32>", "texture_3d<f32>", "texture_2d<u32>"


# --- size checks and helpers ------------------------------------------------------------------------------------

def size_of(depth: np.ndarray) -> tuple[int, int]:
    """(width, height) of a depth map."""
    h, w = depth.shape[:2]
    return w, h


def check_2d(gpu: Gpu, w: int, h: int, what: str = "") -> None:
    """The map is a w x h 2D texture (a height map of up to the adapter's limit per side fits)."""
    side = gpu.device.limits["max-texture-dimension-2d"]
    check_texture_size(gpu, w, h, what or "the map", f"use a height map of at most {side} texels per side")


def fits_texels(w: int, h: int, texels: int) -> str:
    """The fix for a w x h height map beyond ``texels`` texels: the largest map of its shape within."""
    scale = min(1.0, (texels / (w * h)) ** 0.5)
    return f"use a height map of at most {texels} texels (e.g. {max(1, int(w * scale))}x{max(1, int(h * scale))})"


def uint_texture(gpu: Gpu, data: np.ndarray, label: str) -> wgpu.GPUTexture:
    """An rgba32uint 2D texture holding ``data`` (uint32 (H, W, 4))."""
    h, w = data.shape[:2]
    check_2d(gpu, w, h, label)
    with allocating(gpu, label, w * h * 16, "use a smaller height map"):
        texture = gpu.device.create_texture(label=label, size=(w, h, 1), format="rgba32uint",
                                            usage=wgpu.TextureUsage.TEXTURE_BINDING | wgpu.TextureUsage.COPY_DST)
    data = np.ascontiguousarray(data, np.uint32)
    gpu.device.queue.write_texture({"texture": texture, "mip_level": 0, "origin": (0, 0, 0)}, data,
                                   {"offset": 0, "bytes_per_row": w * 16, "rows_per_image": h}, (w, h, 1))
    return texture


def map_backend(gpu: Gpu, w: int, h: int) -> str:
    """The backend a 2D map of a w x h height map is built with for the renderer: "auto" (the GPU kernel) where the
    map's storage buffers (4 bytes a texel) fit the adapter's limit, else "cpu" (a scene cannot pick a backend)."""
    from .compute import compute_for

    return "auto" if w * h * 4 <= compute_for(gpu).max_buffer else "cpu"
