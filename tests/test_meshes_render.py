"""Meshes through the normal render path (wgpuviewer.api.render): glTF and OBJ files with their own textures and
with a scene material, and the curved builtins under a ray-search technique."""

from __future__ import annotations

import numpy as np
import pytest

from tests.test_meshes import (
    QUAD_FACES,
    QUAD_POSITIONS,
    QUAD_UV,
    mesh_scene,
    write_glb,
    write_gltf,
    write_gltf_external_png,
    write_obj,
)
from wgpuviewer import api, meshes

pytestmark = pytest.mark.requires_gpu

SIZE = (64, 48)


@pytest.fixture(autouse=True)
def fresh_cache():
    meshes.clear_cache()
    yield
    meshes.clear_cache()


@pytest.mark.parametrize("writer", [lambda d: write_glb(d / "panel.glb"), write_gltf_external_png, write_obj],
                         ids=["glb", "gltf+png", "obj+mtl+png"])
def test_mesh_files_render_their_own_texture_upright(tmp_path, writer):
    path = writer(tmp_path)
    albedo = api.render(mesh_scene(tmp_path, path.name), "pom", SIZE, mode="albedo")
    top, bottom = albedo[16, 32], albedo[32, 32]  # the quad spans rows 12..36 and columns 20..44
    assert top[0] > 0.9 and top[2] < 0.1, top  # red: the image's top rows
    assert bottom[2] > 0.9 and bottom[0] < 0.1, bottom
    assert np.isnan(api.render(mesh_scene(tmp_path, path.name), "basic", SIZE, mode="uv")[2, 2]).all()


def test_a_mesh_renders_with_a_scene_material(tmp_path):
    write_glb(tmp_path / "panel.glb")
    albedo = api.render(mesh_scene(tmp_path, "panel.glb", material="bricks"), "pom", SIZE, mode="albedo")
    quad = albedo[14:34, 22:42]
    assert np.isfinite(quad).all() and quad[..., 0].mean() > quad[..., 2].mean()  # bricks: red-brown, no blue half
    assert np.abs(quad[:8].mean(axis=(0, 1)) - quad[-8:].mean(axis=(0, 1))).max() < 0.15


def test_curved_builtins_render_under_a_ray_search(tmp_path):
    path = tmp_path / "curved.toml"
    objects = "".join(f'[[objects]]\ntype = "{kind}"\nmaterial = "bricks"\nsize = {list(size)}\n'
                      f"position = [{x}, 0.0, 0.0]\nrotation = [20.0, 0.0, 0.0]\n"
                      for (kind, size), x in zip([("sphere", (0.5,)), ("cylinder", (0.4, 0.9)), ("torus", (0.4, 0.15))],
                                                 (-1.3, 0.0, 1.3)))
    path.write_text('[camera]\nposition = [0.0, 0.0, 4.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 45\n'
                    '[materials.bricks]\nalbedo = "builtin:bricks"\nheight = "builtin:bricks"\nuv_scale = [4.0, 2.0]\n'
                    + objects)
    depth = api.render(path, "pom", (96, 48), mode="depth")
    drawn = np.isfinite(depth)
    for column in (29, 48, 67):  # around each shape's centre (x / 3.31 + 1) * 48, at about the camera's distance
        assert drawn[:, column - 3:column + 4].sum() > 40, column
    assert 3.0 < np.nanmin(depth) < np.nanmax(depth) < 4.5
    color = api.render(path, "pom", (96, 48))
    assert np.isfinite(color).all()


def test_a_mesh_with_uvs_beyond_the_unit_square_is_drawn_whole(tmp_path):
    """Files tile textures by their uvs (here -1 to 2 across the quad): under repeat addressing all of it shows, and
    a curved builtin's seam (u = 1 next to u = 0) is no edge either."""
    write_gltf(tmp_path / "tiled.gltf", QUAD_POSITIONS, QUAD_UV * 3 - 1, QUAD_FACES)
    uv = api.render(mesh_scene(tmp_path, "tiled.gltf", material="bricks"), "pom", SIZE, mode="uv")
    assert np.isfinite(uv[14:34, 22:42]).all()
    sphere = tmp_path / "sphere.toml"
    sphere.write_text('[camera]\nposition = [0.0, 0.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 40\n[materials.b]\n'
                      'albedo = "builtin:bricks"\nheight = "builtin:bricks"\nheight_scale = 0.1\nuv_scale = [4.0, 2.0]\n'
                      '[[objects]]\ntype = "sphere"\nmaterial = "b"\nsize = [1.0]\n')
    seam = api.render(sphere, "pom", SIZE, mode="uv")[8:40, 30:34]  # the seam faces the camera (u = 0 at +Z)
    assert np.isfinite(seam).all()
