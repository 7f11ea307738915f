"""The scene model: frozen dataclasses a validated scene is made of (``Scene``, ``Camera``, ``Light``, ``Material``,
``SceneObject``) and the choices their fields take (``SHADOW_MODES``, ``ADDRESS_MODES``, ``OBJECT_TYPES``,
``CHANNELS``), with the defaults a scene leaves out (``DEFAULT_LIGHT``, ``MESH_DEFAULT_COLOR``).

Conventions: right-handed world, +Y up; angles in degrees; colours are linear RGB in [0, 1].
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from wgpuviewer.meshes import BUILTIN_SHAPES
from wgpuviewer.textures import TextureRef

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Camera:
    """Perspective camera; ``fov`` is the vertical field of view in degrees, ``up`` is unit length."""

    position: Vec3
    target: Vec3
    up: Vec3 = (0.0, 1.0, 0.0)
    fov: float = 60.0
    near: float = 0.05
    far: float = 100.0


@dataclass(frozen=True)
class Light:
    """A directional light (``direction``: unit vector the light travels along) or a point light."""

    type: str
    color: Vec3 = (1.0, 1.0, 1.0)
    intensity: float = 1.0
    direction: Vec3 | None = None
    position: Vec3 | None = None


@dataclass(frozen=True)
class Material:
    """Surface textures and relief settings.

    ``normal`` None means: derive normals from the height map if there is one, else flat.
    ``height_is_depth`` records that the scene gave ``depth`` (0 = top) rather than ``height``
    (1 = top); textures.load_height / load_depth take it as ``is_depth``. ``height_scale`` is the
    relief depth in UV units; ``uv_scale`` tiles the textures and ``uv_offset`` then shifts them, in tiles
    (glTF's KHR_texture_transform order: ``uv * uv_scale + uv_offset``). ``maps``: (slot, file) of the
    precomputed maps the scene names (``[materials.X.maps]``), each checked against the height file it was built
    from; the renderer serves them instead of building those slots (``maptools.cache.serving``). ``shadows``: the
    relief's self-shadowing (``SHADOW_MODES``); ``depth_offset`` writes the traced hit's depth so other geometry
    intersects the relief; ``address``: ``repeat`` tiles the textures, ``clamp`` makes the uv square the relief's
    extent (rays leaving it before a hit are discarded: silhouettes).
    """

    name: str
    albedo: TextureRef
    normal: TextureRef | None = None
    normal_y: str = "opengl"
    height: TextureRef | None = None
    height_is_depth: bool = False
    height_scale: float = 0.05
    uv_scale: tuple[float, float] = (1.0, 1.0)
    uv_offset: tuple[float, float] = (0.0, 0.0)
    maps: tuple[tuple[str, TextureRef], ...] = ()
    shadows: str = "off"
    depth_offset: bool = False
    address: str = "repeat"


#: Self-shadowing modes of a material (``shadows = ...``; the render flag ``--shadows`` overrides every material).
SHADOW_MODES = ("off", "hard", "soft")
#: Texture addressing of a material: ``repeat`` tiles, ``clamp`` ends the relief at the uv domain's edge.
ADDRESS_MODES = ("repeat", "clamp")


@dataclass(frozen=True)
class SceneObject:
    """A shape with a material. Plane: in XZ facing +Y, size (width along X, depth along Z);
    quad: in XY facing +Z, size (width along X, height along Y); box: size (x, y, z); sphere: size (radius,);
    cylinder: along Y, size (radius, height); torus: around Y, size (major radius, minor radius) (``meshes``).
    mesh: the triangles of ``file`` (glTF or OBJ; ``node``: one node or object of it), scaled by ``scale``; its
    ``size`` is that of the origin-centred box holding the scaled mesh.
    ``rotation`` is Euler XYZ in degrees, applied before ``position``.
    """

    type: str
    material: str
    size: tuple[float, ...]
    position: Vec3 = (0.0, 0.0, 0.0)
    rotation: Vec3 = (0.0, 0.0, 0.0)
    file: Path | None = None
    node: str | None = None
    scale: Vec3 = (1.0, 1.0, 1.0)


@dataclass(frozen=True)
class Scene:
    """A validated scene. ``technique_params`` holds the full resolved parameters of every
    technique in ``techniques`` (registry defaults merged with the scene's ``[techniques.NAME]``).
    """

    path: Path | None
    name: str
    camera: Camera
    lights: tuple[Light, ...]
    materials: dict[str, Material]
    objects: tuple[SceneObject, ...]
    technique: str
    techniques: tuple[str, ...]
    technique_params: dict[str, dict]
    background: Vec3 = (0.02, 0.02, 0.03)


#: Builtin object type -> how many numbers its ``size`` has (``meshes.BUILTIN_SHAPES`` names them).
OBJECT_SIZES = {object_type: len(keys) for object_type, (keys, _) in BUILTIN_SHAPES.items()}
#: Every object type: the builtins and ``mesh`` (a glTF or OBJ file).
OBJECT_TYPES = (*OBJECT_SIZES, "mesh")
#: Albedo of a mesh whose file gives it no material.
MESH_DEFAULT_COLOR = (0.8, 0.8, 0.8)
#: Which channel of a height/depth file is the height (``channel = ...``).
CHANNELS = ("auto", "r", "g", "b", "a")


def normalise(v: tuple[float, ...]) -> Vec3:
    length = math.hypot(*v)
    return tuple(c / length for c in v)


#: Used when a scene gives no lights: from above, slightly from the front left.
DEFAULT_LIGHT = Light("directional", direction=normalise((0.4, -1.0, -0.3)))
