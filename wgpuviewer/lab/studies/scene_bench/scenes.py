"""The scenes the scene benchmark measures and the views it sees each from.

``SCENES`` names the default ones: the showcase, the default scene and the curved/mesh scene (files under
``scenes/``), and ``photos``, a texture set of scikit-image's bundled photographs (brick, gravel, grass: grey,
brighter = higher, each its own albedo) made here, its pictures written to a work folder. Any other name is a scene
file's path. Each scene is seen from ``VIEWS``, derived from its own camera: ``near`` halfway to the target, ``far``
from 1.8 times as far, and ``grazing`` from the same distance but 8 degrees above the target's foot on the ground
plane y = 0 (the floors of the scenes lie there): the floor then fills the lower frame at 80-90 degrees from its
normal.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.bench.view import load_heightmap
from wgpuviewer.scene import Camera, Scene, default_scene_path, load_scene, parse_scene

#: Scene files of the default scenes, relative to scenes/ (the package wgpuviewer.scenes).
SCENE_FILES = {"showcase": "showcase.toml", "default": "default.toml", "curved": "curved.toml"}
PHOTOS = "photos"
SCENES = ("showcase", "default", PHOTOS, "curved")
VIEWS = ("near", "far", "grazing")
NEAR, FAR = 0.5, 1.8  # the camera's distance to its target, times the scene's
GRAZING_DEGREES = 8.0  # the grazing camera's elevation above the target's foot on y = 0
PHOTO_SIZE = 256  # texels per side of the photographs (area-downscaled from 512: the maps build in seconds)

#: The photographs' scene: a brick floor, a gravel slab and a grass wall; {brick}, {gravel}, {grass} are the pictures.
PHOTOS_SCENE = """
[scene]
name = "Photographs"
techniques = ["auto", "maxmip", "pom", "basic"]
background = [0.05, 0.05, 0.06]
[camera]
position = [0.4, 1.5, 3.3]
target = [0.0, 0.3, 0.0]
fov = 55.0
far = 40.0
[[lights]]
type = "directional"
direction = [-0.4, -1.0, -0.6]
intensity = 0.9
[[lights]]
type = "point"
position = [-1.0, 1.0, 1.2]
color = [1.0, 0.8, 0.6]
intensity = 1.2
[materials.brick]
albedo = {brick}
height = {brick}
height_scale = 0.05
uv_scale = [3.0, 3.0]
[materials.gravel]
albedo = {gravel}
height = {gravel}
height_scale = 0.04
uv_scale = [2.0, 2.0]
[materials.grass]
albedo = {grass}
height = {grass}
height_scale = 0.06
uv_scale = [3.0, 1.5]
[[objects]]
type = "plane"
material = "brick"
size = [6.0, 6.0]
[[objects]]
type = "box"
material = "gravel"
size = [1.4, 0.3, 1.0]
position = [0.9, 0.15, -0.4]
rotation = [0.0, 25.0, 0.0]
[[objects]]
type = "quad"
material = "grass"
size = [6.0, 2.5]
position = [0.0, 1.25, -2.0]
"""


def check_scene(name: str) -> None:
    """A UserError naming SCENE unless ``name`` is a default scene's name or an existing file."""
    if name not in SCENES and not Path(name).is_file():
        raise UserError(f"SCENE {name!r}: neither a scene file nor one of {', '.join(SCENES)}; give a .toml path")


def load(name: str, workdir: Path) -> Scene:
    """The scene ``name`` (module docstring); the photographs' pictures go to ``workdir``."""
    if name == PHOTOS:
        pictures = {m: load_heightmap(m, 0, workdir, PHOTO_SIZE).texture for m in ("brick", "gravel", "grass")}
        return parse_scene(PHOTOS_SCENE.format(**pictures), workdir / "photos.toml")
    if name in SCENE_FILES:
        return load_scene(default_scene_path().parent / SCENE_FILES[name])
    return load_scene(name)


def views(camera: Camera) -> dict[str, Camera]:
    """The cameras of ``VIEWS`` derived from ``camera`` (module docstring)."""
    position, target = np.asarray(camera.position, np.float64), np.asarray(camera.target, np.float64)
    offset = position - target
    distance = float(np.linalg.norm(offset))
    across = np.array([offset[0], 0.0, offset[2]])
    across = across / np.linalg.norm(across) if np.linalg.norm(across) > 1e-9 else np.array([0.0, 0.0, 1.0])
    foot = np.array([target[0], 0.0, target[2]])
    rise = math.radians(GRAZING_DEGREES)
    grazing = foot + distance * (math.cos(rise) * across + np.array([0.0, math.sin(rise), 0.0]))
    return {
        "near": replace(camera, position=_vec(target + NEAR * offset)),
        "far": replace(camera, position=_vec(target + FAR * offset)),
        "grazing": replace(camera, position=_vec(grazing), target=_vec(foot)),
    }


def _vec(v: np.ndarray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))
