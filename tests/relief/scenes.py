"""Small test scenes built in code."""

from __future__ import annotations


def plane_scene(technique: str, params: str = "", *, position=(0.1, 0.5, 0.8), height_scale=0.08,
                map_size=64) -> str:
    """TOML of a grey unit plane with a bumps relief, seen from ``position``, offering one technique whose
    ``[techniques.NAME]`` table holds ``params`` (TOML lines)."""
    return f"""
[scene]
techniques = ["{technique}"]
[camera]
position = [{position[0]}, {position[1]}, {position[2]}]
target = [0.0, 0.0, 0.0]
fov = 50
[materials.m]
albedo = [0.8, 0.8, 0.8]
height = {{ builtin = "bumps", size = [{map_size}, {map_size}] }}
height_scale = {height_scale}
[[objects]]
type = "plane"
material = "m"
size = [1.0, 1.0]
[techniques.{technique}]
{params}
"""


def material_scene(techniques, material: str, *, position=(0.0, 1.0, 2.0), camera: str = "", extra: str = "") -> str:
    """TOML of a 2x2 plane with material ``m`` (its TOML lines ``material``), offering ``techniques``, seen from
    ``position`` (more ``[camera]`` lines in ``camera``); ``extra`` is appended (lights, objects)."""
    names = ", ".join(f'"{t}"' for t in techniques)
    return f"""
[scene]
techniques = [{names}]
[camera]
position = [{position[0]}, {position[1]}, {position[2]}]
target = [0.0, 0.0, 0.0]
{camera}
[materials.m]
{material}
[[objects]]
type = "plane"
material = "m"
size = [2.0, 2.0]
{extra}
"""
