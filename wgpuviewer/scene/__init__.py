"""Scenes: TOML files validated into frozen dataclasses.

What lives here, one job a module: ``model`` (the frozen dataclasses a scene is made of and the choices their fields
take), ``table`` (reading TOML tables with one-line errors), ``limits`` (the format's limits such as ``MAX_LIGHTS``
and the geometry float32 renders correctly: ``MAX_VIEW_RATIO``, ``MAX_TEXEL_COORDINATE``), ``folders`` (material
folders: files found by name, the note on what a folder gave, ``--material DIR``), ``materials`` (``[materials.X]``
tables: textures, folders, named maps), ``parse`` (a scene file read: ``load_scene``, ``parse_scene``).

Conventions: right-handed world, +Y up; angles in degrees; colours are linear RGB in [0, 1].
Textures are only referenced here (textures.TextureRef); textures.py loads them lazily.
Every problem is a one-line UserError naming the file, the key path, the value and what is
expected. ``scenes/default.toml`` documents the format.

May import: ``wgpuviewer.core``, ``wgpuviewer.techniques`` (the technique registry: scenes name techniques and
their parameters) and the other scene modules (``textures``, ``meshes``, ``camera``); never ``relief``, the viewer
or the lab. The names below are the package's interface; import the rest from its module.
"""

from .folders import with_folder_material
from .limits import MAX_LIGHTS, uv_scale_problem
from .model import SHADOW_MODES, Camera, Light, Material, Scene, SceneObject
from .parse import default_scene_path, load_scene, parse_scene

__all__ = [
    "MAX_LIGHTS",
    "SHADOW_MODES",
    "Camera",
    "Light",
    "Material",
    "Scene",
    "SceneObject",
    "default_scene_path",
    "load_scene",
    "parse_scene",
    "uv_scale_problem",
    "with_folder_material",
]
