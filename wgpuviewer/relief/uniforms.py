"""The render entry's uniforms, packed from the scene: the Frame (camera, mode, the scene's lights), each object's
Object record (model and normal matrices, the material's uv transform). Their layouts are ``shaders.FRAME``,
``OBJECT`` and ``LIGHT`` (generated, ``core.structs``); a draw's TraceParams are ``shaders.pack_trace_params``."""

from __future__ import annotations

import numpy as np

from wgpuviewer import camera as cam
from wgpuviewer.scene import Camera, Scene
from wgpuviewer.techniques import Technique

from .shaders import FRAME, LIGHT, MAX_LIGHTS, OBJECT

#: Frame.mode values (render.wgsl's MODE_* constants; "depth" draws its own entry point, fs_view_depth).
MODES = {"color": 0, "cost": 1, "uv": 2, "layer_depth": 3, "layers": 4, "albedo": 5, "depth": 6}


def scene_lights(scene) -> np.ndarray:
    """The Frame uniform's light records (LIGHT, MAX_LIGHTS of them; unused ones zero) for ``scene``'s lights."""
    lights = np.zeros(MAX_LIGHTS, LIGHT.dtype)
    for i, light in enumerate(scene.lights):  # the scene checked the count (MAX_LIGHTS)
        if light.type == "directional":
            lights["vector"][i] = [*(-np.asarray(light.direction)), 0.0]  # towards the light
        else:
            lights["vector"][i] = [*light.position, 1.0]
        lights["color"][i] = [*(np.asarray(light.color) * light.intensity), 0.0]
    return lights


def frame_data(scene: Scene, lights: np.ndarray, camera: Camera, size: tuple[int, int], mode: str,
               technique: Technique, params: dict) -> bytes:
    """The Frame uniform of one frame: ``camera`` at the aspect of ``size``, ``mode``, the cost and layers views'
    scales of ``technique`` at ``params``, and ``lights`` (``scene_lights``)."""
    w, h = size
    view_proj = cam.perspective(camera.fov, w / h, camera.near, camera.far) @ cam.look_at(
        camera.position, camera.target, camera.up
    )
    lo, hi = technique.layer_range(params)
    return FRAME.pack({"view_proj": cam.to_wgsl(view_proj), "camera_pos": [*camera.position, 0.0],
                       "light_count": len(scene.lights), "mode": MODES[mode],
                       "cost_scale": technique.cost_scale(params), "layer_lo": lo, "layer_hi": hi,
                       "lights": lights})


def object_data(obj, material) -> bytes:
    """The Object uniform of a scene object drawn with ``material``."""
    model = cam.translation(obj.position) @ cam.rotation_xyz(obj.rotation)
    normal_matrix = np.eye(4)
    normal_matrix[:3, :3] = np.linalg.inv(model[:3, :3]).T
    return OBJECT.pack({"model": cam.to_wgsl(model), "normal_matrix": cam.to_wgsl(normal_matrix),
                        "uv_transform": [*material.uv_scale, *uv_offset(material)]})


def uv_offset(material) -> tuple[float, float]:
    """The offset a material's uv gets on the GPU: under repeat addressing its fraction (``offset_fraction``);
    under clamp addressing the offset as it is, since there the uv square is the relief's one tile and a whole
    tile moves the texture off the face (its pixels are discarded)."""
    if material.address == "clamp":
        return tuple(float(x) for x in material.uv_offset)
    return offset_fraction(material.uv_offset)


def offset_fraction(uv_offset: tuple[float, float]) -> tuple[float, float]:
    """``Material.uv_offset`` less its whole tiles, in float64 (``x - floor(x)``: exact for x >= 0, within 2^-53
    below), in [0, 1]. Repeating materials move nothing by whole tiles; what reaches the GPU's float32 is the
    fraction alone, and an offset of 1e5 tiles draws exactly what its fraction draws."""
    offset = np.asarray(uv_offset, np.float64)
    return tuple(float(x) for x in offset - np.floor(offset))
