"""A material's textures as the renderer builds them on first use: its own (albedo, normal: loaded, or the normal
derived from the height) and the height-derived maps of ``maps.MAP_SLOTS`` (built by maptools, cached on disk).
Problems are reported against the scene key the texture comes from (``TextureRef.origin``), not against a map the
user never named."""

from __future__ import annotations

import contextlib

import numpy as np
import wgpu

from maptools.cache import cached_generate, serving
from wgpuviewer import textures
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import Gpu, create_texture, mip_chain
from wgpuviewer.core.images import read_header

from .maps import MAP_SLOTS

#: Formats of the material textures the renderer loads itself (the height-derived ones come from maps.py).
MATERIAL_FORMATS = {"albedo": "rgba16float", "normal": "rgba8unorm"}


def derived_texture(gpu: Gpu, material, kind: str, depth: np.ndarray, label: str) -> wgpu.GPUTexture:
    """Slot ``kind`` (a derived one) of ``material``, built from its ``depth`` data."""
    with building(material, kind):
        return MAP_SLOTS[kind].build(gpu, depth, material.height_scale, label)


def material_texture(gpu: Gpu, material, kind: str, label: str, created: list[str]) -> wgpu.GPUTexture:
    """The material's own ``albedo`` or ``normal`` texture, with its mip chain (a normal map derived from the
    height is logged in ``created`` as "map:MATERIAL.normal")."""
    if kind == "normal":
        data = normal_data(material, created)  # our own copy: encoded in place, n * 0.5 + 0.5
        data *= 0.5
        data += 0.5
        source = material.normal or material.height
    else:
        data = textures.load_albedo(material.albedo)
        source = material.albedo
    with reported_against(source, kind):
        return create_texture(gpu, mip_chain(data), MATERIAL_FORMATS[kind], label)


def depth_data(material) -> np.ndarray:
    """The material's depth map (D = 1 - height); a 1x1 zero (the top plane) without relief."""
    if material.height is None:  # no relief: the surface is the top plane
        return np.zeros((1, 1), np.float32)
    return textures.load_depth(material.height, material.height_is_depth)


def normal_data(material, created: list[str]) -> np.ndarray:
    """Normals in the shader's tangent frame: x = u, y = v (image rows down)."""
    if material.normal is not None:
        normals = textures.load_normal_map(material.normal, material.normal_y).copy()
        normals[:, :, 1] *= -1  # OpenGL convention: +y points to image row 0, i.e. towards -v
        return normals
    if material.height is None:
        return np.array([[[0.0, 0.0, 1.0]]], np.float32)
    height = 1.0 - textures.load_depth(material.height, material.height_is_depth)
    created.append(f"map:{material.name}.normal")
    # Slopes of the actual relief: height_scale UV units deep over a texture width of 1 UV unit.
    # maptools' "directx" convention has +y towards increasing rows, which is +v here.
    strength = material.height_scale * height.shape[1]
    with reported_against(material.height, "normal"):
        return cached_generate("normal", height, backend="cpu", strength=strength, y="directx")


def height_size(material) -> tuple[int, int]:
    """(width, height) of a material's height map without loading it: a builtin's size, a file's header; (1, 1)
    without one (the renderer's flat depth)."""
    ref = material.height
    if ref is None:
        return 1, 1
    if ref.kind == "file":
        with textures.reported_against(ref):
            header = read_header(ref.path)
        return header.width, header.height
    return tuple(ref.size)


@contextlib.contextmanager
def building(material, kind: str):
    """Around the build of a material's derived map ``kind``: the maps the scene names for the material
    (``Material.maps``) are served from their files (``maptools.cache.serving``), and problems are reported against
    the height map's key, except a named map's, whose messages name its own key."""
    named = {slot: (ref.path, ref.origin) for slot, ref in material.maps}
    with reported_against(None if kind in named else material.height, kind), serving(named):
        yield


@contextlib.contextmanager
def reported_against(ref, kind: str):
    """A texture of slot ``kind`` that cannot be built (too large for a limit or for the adapter's memory, ...) is
    reported against the scene key of the texture it comes from (``ref``; the height map for a derived map), not
    against the map the user never named."""
    try:
        yield
    except UserError as error:
        if ref is None or not ref.origin:
            raise
        raise ref.error(f"its {kind} map cannot be built: {error}") from None
