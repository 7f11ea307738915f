"""The maps an exported module binds, as its trace reads them: built by the slots the renderer and the probe use
(``relief.maps.MAP_SLOTS``, from the disk cache of maptools' maps), read back level by level, and written one
``STEM.SLOT.texture.npz`` per binding (arrays ``level0`` ... ``levelK``, (H, W, C) or (D, H, W, C) texels in the
texture format's own type, and ``format``, ``dimension``, ``binding``), with the uniform's values in
``STEM.relief_params.json``.

May import: ``wgpuviewer.core``, the technique registry, ``wgpuviewer.relief`` and maptools; never the lab.
"""

from __future__ import annotations

import io
import json
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import wgpu

from wgpuviewer.core.gpu import Gpu
from wgpuviewer.core.io import write_bytes
from wgpuviewer.relief.maps import MAP_SLOTS, depth_range

from .module import FIRST_TEXTURE_BINDING, Export
from .sources import texture_file

_FORMAT = re.compile(r"^(r|rg|rgba)(8|16|32)(unorm|snorm|uint|sint|float)$")
_TYPES = {("8", "unorm"): np.uint8, ("8", "snorm"): np.int8, ("8", "uint"): np.uint8, ("8", "sint"): np.int8,
          ("16", "float"): np.float16, ("16", "uint"): np.uint16, ("16", "sint"): np.int16,
          ("32", "float"): np.float32, ("32", "uint"): np.uint32, ("32", "sint"): np.int32}


def texel_type(fmt: str) -> tuple[np.dtype, int]:
    """(numpy dtype, channels) of a plain colour format such as r16float or rgba32uint."""
    match = _FORMAT.match(fmt)
    if not match:
        raise ValueError(f"texture format {fmt!r}: not a plain colour format")
    return np.dtype(_TYPES[match.group(2), match.group(3)]), len(match.group(1))


class _Readable:
    """A device whose new textures can also be copied from (COPY_SRC): the slots make theirs for sampling only,
    and ``texture_levels`` reads them back."""

    def __init__(self, device: wgpu.GPUDevice):
        self._device = device

    def __getattr__(self, name: str):
        return getattr(self._device, name)

    def create_texture(self, **kwargs) -> wgpu.GPUTexture:
        return self._device.create_texture(**{**kwargs, "usage": kwargs["usage"] | wgpu.TextureUsage.COPY_SRC})


def slot_textures(gpu: Gpu, export: Export, height: np.ndarray, height_scale: float,
                  readable: bool = False) -> dict[str, wgpu.GPUTexture]:
    """The export's textures by slot name, built from ``height`` (H, W in [0, 1]) as the renderer builds them;
    ``readable``: they can be read back (``texture_levels``)."""
    depth = 1.0 - np.asarray(height, np.float64)
    if readable:
        gpu = replace(gpu, device=_Readable(gpu.device), cache={})
    return {name: MAP_SLOTS[name].build(gpu, depth, height_scale, f"export:{name}") for name in export.textures}


def params_values(gpu: Gpu, export: Export, height: np.ndarray, height_scale: float) -> dict:
    """The ``ReliefParams`` uniform's values for ``height`` (the depth range as the depth texture holds it)."""
    lo, hi = depth_range(1.0 - np.asarray(height, np.float64), gpu.depth_format)
    values = {"height_scale": height_scale, "depth_width": height.shape[1], "depth_height": height.shape[0],
              "depth_min": lo, "depth_max": hi, **export.values}
    return {name: values[name] for name, _ in export.params.fields if not name.startswith("_")}


def texture_levels(device: wgpu.GPUDevice, texture: wgpu.GPUTexture) -> list[np.ndarray]:
    """Every mip level of a 2D or 3D texture: (H, W, C) or (D, H, W, C) arrays of its format's type."""
    dtype, channels = texel_type(str(texture.format))
    w, h, d = texture.size
    three_d = texture.dimension == "3d"
    levels = []
    for m in range(texture.mip_level_count):
        lw, lh, ld = max(w >> m, 1), max(h >> m, 1), max(d >> m, 1) if three_d else 1
        raw = device.queue.read_texture({"texture": texture, "mip_level": m, "origin": (0, 0, 0)},
                                        {"offset": 0, "bytes_per_row": lw * channels * dtype.itemsize,
                                         "rows_per_image": lh}, (lw, lh, ld if three_d else d))
        a = np.frombuffer(raw, dtype).reshape(-1, lh, lw, channels).copy()
        levels.append(a if three_d else a.reshape(-1, lw, channels) if d == 1 else a)
    return levels


def write_maps(gpu: Gpu, export: Export, height: np.ndarray, height_scale: float, folder: Path,
               stem: str) -> list[Path]:
    """``STEM.SLOT.texture.npz`` for every texture the export binds and ``STEM.relief_params.json``, in
    ``folder``; the paths written."""
    written = []
    for index, (name, texture) in enumerate(slot_textures(gpu, export, height, height_scale, True).items()):
        levels = texture_levels(gpu.device, texture)
        buffer = io.BytesIO()
        np.savez(buffer, **{f"level{i}": a for i, a in enumerate(levels)}, format=np.array(str(texture.format)),
                 dimension=np.array(str(texture.dimension)), binding=np.array(FIRST_TEXTURE_BINDING + index))
        path = folder / texture_file(stem, name)
        write_bytes(path, buffer.getvalue())
        written.append(path)
    params = folder / f"{stem}.relief_params.json"
    write_bytes(params, (json.dumps(params_values(gpu, export, height, height_scale), indent=1) + "\n").encode())
    return [*written, params]
