"""End-to-end sign conventions: a step in the height map, lit from one side, seen from above.

A step that rises along +u (or +v) has a normal tilted towards -u (-v): it is bright when the light
sits on the -u (-v) side and dark when it sits on the other. This pins the tangent frame, the
normal-map derivation and the shader's lighting together.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.relief.scenes import plane_scene
from wgpuviewer import camera as cam
from wgpuviewer import textures
from wgpuviewer.relief.output import mode_data
from wgpuviewer.relief.reference import exact_hit, uv_error_texels
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.scene import load_scene

SCENE = """
scene = {{ techniques = ["normal", "pom"] }}
# screen up = -Z = towards v = 0, so screen rows follow texture rows
camera = {{ position = [0.0, 2.0, 0.0], target = [0.0, 0.0, 0.0], up = [0.0, 0.0, -1.0], fov = 40 }}
[[lights]]
type = "directional"
direction = {direction}
[materials.m]
albedo = [0.8, 0.8, 0.8]
height = "step.npy"
height_scale = 0.05
[[objects]]
type = "plane"
material = "m"
size = [1.0, 1.0]
"""


def render_step(tmp_path, gpu, axis: str, light_travels: list[float], technique="normal") -> np.ndarray:
    h = np.zeros((64, 64), np.float32)
    if axis == "u":
        h[:, 32:] = 1.0  # rises with u at the centre column
    else:
        h[32:, :] = 1.0  # rises with v at the centre row
    np.save(tmp_path / "step.npy", h)
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(direction=light_travels))
    image = Renderer(load_scene(path), gpu).render(technique, (64, 64))
    grey = mode_data(image, "color").mean(axis=2)
    profile = grey[28:36, 20:44].mean(axis=0) if axis == "u" else grey[20:44, 28:36].mean(axis=1)
    return profile


@pytest.mark.parametrize("axis", ["u", "v"])
def test_step_faces_the_light_on_its_low_side(tmp_path, gpu, axis):
    # The light travels towards +u (+v): it sits on the -u (-v) side, which the rising step faces.
    towards_plus = [1.0, -1.0, 0.0] if axis == "u" else [0.0, -1.0, 1.0]
    towards_minus = [-1.0, -1.0, 0.0] if axis == "u" else [0.0, -1.0, -1.0]
    lit = render_step(tmp_path, gpu, axis, towards_plus)
    shaded = render_step(tmp_path, gpu, axis, towards_minus)
    flat = np.median(lit)
    assert lit.max() > flat + 0.05, lit
    assert shaded.min() < flat - 0.1, shaded


FRAGMENT_SCENE = plane_scene("pom", "layers = 256")


def test_fragment_path_matches_the_reference(tmp_path, gpu):
    """The rendered hit UV of every pixel equals the float64 exact hit of that pixel's view ray.

    This checks what the probe cannot: the fragment shader's tangent frame and view vector.
    """
    path = tmp_path / "scene.toml"
    path.write_text(FRAGMENT_SCENE)
    scene = load_scene(path)
    size = (96, 96)
    image = Renderer(scene, gpu).render("pom", size)
    hit_uv = mode_data(image, "uv")

    # Each pixel's ray from the camera, intersected with the plane y = 0 (u = x + 0.5, v = z + 0.5).
    c = scene.camera
    inv = np.linalg.inv(cam.perspective(c.fov, 1.0, c.near, c.far) @ cam.look_at(c.position, c.target, c.up))
    j, i = np.mgrid[0 : size[1], 0 : size[0]]
    ndc = np.stack([(i + 0.5) / size[0] * 2 - 1, 1 - (j + 0.5) / size[1] * 2, np.ones_like(i, float), np.ones_like(i, float)], -1)
    far = ndc @ inv.T
    far = far[..., :3] / far[..., 3:]
    eye = np.asarray(c.position)
    direction = far - eye
    s = -eye[1] / direction[..., 1]
    point = eye + direction * s[..., None]
    uv0 = np.stack([point[..., 0] + 0.5, point[..., 2] + 0.5], -1)
    to_eye = eye - point
    to_eye /= np.linalg.norm(to_eye, axis=-1, keepdims=True)
    v_ts = np.stack([to_eye[..., 0], to_eye[..., 2], to_eye[..., 1]], -1)  # T = +X, B = +Z, N = +Y

    covered = image.covered & (uv0 > 0.02).all(-1) & (uv0 < 0.98).all(-1)
    assert covered.sum() > 2000
    height = textures.builtin_height("bumps", (64, 64))
    ref = exact_hit(1.0 - height, uv0[covered], v_ts[covered], 0.08)
    err = uv_error_texels(hit_uv[covered], ref.uv, (64, 64))
    # 256 layers + interpolation, 8-bit filter weights on the GPU, float32 pixel positions
    assert np.percentile(err, 95) < 0.25, np.percentile(err, [50, 95, 100])
