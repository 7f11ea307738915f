"""What a scene may hold: the format's limits (``MAX_LIGHTS``: the renderer's Frame uniform holds that many) and
the geometry float32 renders correctly (``MAX_DEPTH_RANGE``, ``MAX_VIEW_RATIO``, ``MAX_TEXEL_COORDINATE``), with
the checks against them (``check_geometry``, ``texel_coordinate_problem``, ``uv_scale_problem``).
"""

from __future__ import annotations

import math

import numpy as np

from wgpuviewer import camera as cam
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.images import read_header
from wgpuviewer.textures import TextureRef

from .model import Camera, Material, SceneObject
from .table import show_value

#: Most [[lights]] a scene may have: the renderer's Frame uniform holds them all (32 bytes each), and the
#: shader loops over the scene's count only.
MAX_LIGHTS = 256
#: camera.far / camera.near at most: reversed-Z float depth separates surfaces over this range.
MAX_DEPTH_RANGE = 1e12
#: Float32 vertices. The GPU transforms vertices in float32 (24-bit significand): a vertex, or the camera, at
#: distance P from the world origin lands within about P * 2^-24 of where it belongs, an angle of (P / d) * 2^-24
#: seen from a distance d. Held to 2^-8 radian (a quarter of a degree, under 3 pixels of the default 1280x720
#: frame at the default 60-degree field of view): P / d <= 2^16 for every object's reach |position| + |size| / 2,
#: d being the camera's distance to the object (at least camera.near). The camera, within d of the object, is
#: then within (2^16 + 1) d of the origin. Measured on the software adapter at 64x48 pixels: a plane 1 unit below
#: the camera loses pixels from P / d = 7e5 on and vanishes beyond 2e7. (The perspective study's largest
#: coordinate offset, 1e7 texels, reaches P / d = 2.2e4.)
MAX_VIEW_RATIO = 2.0 ** 16
#: Largest texel coordinate, uv_scale x the texture's side: beyond 2^24 float32's spacing exceeds one texel, so
#: hit points skip texels and the texture tears.
MAX_TEXEL_COORDINATE = 2 ** 24


def _texture_size(ref: TextureRef | None) -> tuple[int, int]:
    """(width, height) of a texture without loading it: a builtin's size, a file's header; 1x1 for a colour."""
    if ref is None or ref.kind == "color":
        return 1, 1
    if ref.kind == "file":
        header = read_header(ref.path)  # checked when the reference was made: cheap, and it does not fail here
        return header.width, header.height
    return ref.size


def texel_coordinate_problem(uv_scale: tuple[float, float], refs) -> str:
    """Why ``uv_scale`` tiles the textures ``refs`` beyond MAX_TEXEL_COORDINATE ('' when it does not)."""
    sizes = [_texture_size(ref) for ref in refs]
    width, height = max(w for w, _ in sizes), max(h for _, h in sizes)
    reach = max(uv_scale[0] * width, uv_scale[1] * height)
    if reach <= MAX_TEXEL_COORDINATE:
        return ""
    most = [MAX_TEXEL_COORDINATE / width, MAX_TEXEL_COORDINATE / height]
    return (f"out of range for its {width}x{height} texture: texel coordinates reach {reach:.3g}, beyond the "
            f"{MAX_TEXEL_COORDINATE} up to which float32 addresses every texel; expected uv_scale <= "
            f"[{most[0]:g}, {most[1]:g}]")


def uv_scale_problem(material: Material, uv_scale: tuple[float, float]) -> str:
    """Why tiling ``material``'s textures by ``uv_scale`` goes beyond MAX_TEXEL_COORDINATE ('' when it does not):
    the check a scene's ``uv_scale`` passes, for a tiling given elsewhere (``render --uv-scale``, the Python API)."""
    return texel_coordinate_problem(uv_scale, (material.albedo, material.normal, material.height))


_HALF_EXTENTS = {  # object type -> its half extents (local x, y, z) from its size: the box holding it
    "plane": lambda s: (s[0] / 2, 0.0, s[1] / 2),
    "quad": lambda s: (s[0] / 2, s[1] / 2, 0.0),
    "box": lambda s: (s[0] / 2, s[1] / 2, s[2] / 2),
    "sphere": lambda s: (s[0], s[0], s[0]),
    "cylinder": lambda s: (s[0], s[1] / 2, s[0]),
    "torus": lambda s: (s[0] + s[1], s[1], s[0] + s[1]),
    "mesh": lambda s: (s[0] / 2, s[1] / 2, s[2] / 2),
}


def _distance_to(obj: SceneObject, point) -> float:
    """Float64 distance from ``point`` to the surface of ``obj`` (a plane's or quad's rectangle, a box's faces; the
    box holding a curved shape or a mesh: a lower bound of the distance outside it, the distance to its faces
    inside)."""
    rotation = cam.rotation_xyz(obj.rotation)[:3, :3]
    local = np.abs(rotation.T @ (np.asarray(point, np.float64) - obj.position))
    half = np.asarray(_HALF_EXTENTS[obj.type](obj.size))
    outside = float(np.linalg.norm(np.maximum(local - half, 0.0)))
    return outside if outside > 0 else float(np.min(half - local))  # inside a box: to its nearest face


def check_geometry(src: str, camera: Camera, objects: tuple[SceneObject, ...], raw_objects: list[dict]) -> None:
    """Every object within float32's range for the camera's view of it (MAX_VIEW_RATIO). The camera's own
    |position| is then within (MAX_VIEW_RATIO + 1) times its distance to the nearest object: no check of its own."""
    ratio = MAX_VIEW_RATIO
    for i, (obj, raw) in enumerate(zip(objects, raw_objects, strict=True)):
        d = max(_distance_to(obj, camera.position), camera.near)
        offset = math.hypot(*obj.position)
        reach = offset + math.hypot(*_HALF_EXTENTS[obj.type](obj.size))
        if reach > ratio * d:
            key = "position" if offset > ratio * d else "scale" if obj.type == "mesh" else "size"
            given = raw.get(key, {"position": [0, 0, 0], "scale": 1, "size": list(obj.size)}[key])
            raise UserError(f"{src}: objects[{i}].{key} = {show_value(given)}: out of range, expected "
                            f"|position| + |size| / 2 <= {ratio * d:.4g} (float32 places vertices within 1/4 degree "
                            f"up to {ratio:.0f} x the camera's distance to the object, here {d:.4g}; it reaches "
                            f"{reach:.4g}){_mesh_size(obj) if key == 'scale' else ''}")


def _mesh_size(obj: SceneObject) -> str:
    """What a mesh object's size is made of, for a message blaming its ``scale``."""
    size = ", ".join(f"{x:.4g}" for x in obj.size)
    return f"; the file's mesh at this scale measures [{size}]: give a smaller scale or re-export it in other units"
