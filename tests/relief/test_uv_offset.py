"""Large texture coordinates in the renderer. ``uv_offset`` (a material's texture offset in tiles, after
``uv_scale``) is validated like the other material keys and, under repeat addressing, loses its whole tiles in
float64 before anything is float32, so a tiled material drawn at an offset of 1e5 tiles matches the same material at
offset 0 (under clamp addressing whole tiles move the texture off the face); and each
fragment's ray search runs on the fraction of its uv, so heavy tiling costs only the uv's own float32 rounding."""

from __future__ import annotations

import numpy as np
import pytest

from tests.relief.scenes import material_scene
from wgpuviewer.core.errors import UserError
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.relief.uniforms import offset_fraction
from wgpuviewer.scene import parse_scene

TEXELS = 64
BRICKS = f'{{ builtin = "bricks", size = [{TEXELS}, {TEXELS}] }}'
SIZE = (64, 48)
LARGE = 1e5  # tiles: float32's spacing there is 2^-7 of a tile, half a texel of a 64-texel map
UV_TOLERANCE = 1e-6  # tiles; 6e-5 of a texel


def scene(offset: str | None, techniques=("pom",)):
    lines = f"albedo = {BRICKS}\nheight = {BRICKS}\nheight_scale = 0.06\nuv_scale = [3.0, 3.0]\n"
    if offset is not None:
        lines += f"uv_offset = {offset}\n"
    return parse_scene(material_scene(list(techniques), lines, position=(0.3, 0.9, 1.4)))


def test_the_offset_defaults_to_zero_and_is_read_as_given():
    assert scene(None).materials["m"].uv_offset == (0.0, 0.0)
    assert scene("[100000.25, -3]").materials["m"].uv_offset == (100000.25, -3.0)


@pytest.mark.parametrize(("value", "expected"), [
    ("[1.0]", "materials.m.uv_offset = [1.0]: expected an array of 2 numbers"),
    ("[1.0, 'a']", "materials.m.uv_offset = [1.0, 'a']: expected an array of 2 numbers"),
    ("0.5", "materials.m.uv_offset = 0.5: expected an array of 2 numbers"),
    ("[nan, 0.0]", "materials.m.uv_offset[0] = nan: expected a finite number"),
    ("[0.0, -inf]", "materials.m.uv_offset[1] = -inf: expected a finite number"),
])
def test_a_bad_offset_is_one_line_naming_the_key(value, expected):
    with pytest.raises(UserError) as error:
        scene(value)
    message = str(error.value)
    assert expected in message and "\n" not in message


def test_only_the_fraction_of_the_offset_reaches_the_gpu():
    assert offset_fraction((LARGE, -LARGE)) == (0.0, 0.0)
    assert offset_fraction((LARGE + 0.25, -2.25)) == (0.25, 0.75)  # both exact in float64
    assert offset_fraction((2.0 ** 51 + 0.5, 0.0)) == (0.5, 0.0)  # float64 still holds a half there; float32 not


def uv_texels(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max()) * TEXELS


@pytest.mark.requires_gpu
@pytest.mark.parametrize("fraction", [0.0, 0.25])
def test_a_large_offset_draws_what_its_fraction_draws(gpu, fraction):
    near = Renderer(scene(f"[{fraction}, {fraction}]"), gpu).render("pom", SIZE)
    far = Renderer(scene(f"[{LARGE + fraction}, {LARGE + fraction}]"), gpu).render("pom", SIZE)
    covered = near.covered
    assert covered.mean() > 0.3 and (far.covered == covered).all()
    assert np.abs(far.color.astype(int) - near.color.astype(int)).max() <= 1
    uv, far_uv = near.data[covered][:, :2], far.data[covered][:, :2]
    assert uv_texels(far_uv, uv) <= UV_TOLERANCE * TEXELS
    assert np.abs(far.data[covered][:, 2] - near.data[covered][:, 2]).max() <= 1e-6  # hit depth
    # Adding the offset in float32 on the GPU, after uv * uv_scale, would round every uv to float32's spacing at
    # 1e5 tiles before the search starts: far more than the tolerance above (a quarter texel at worst).
    rounded = (uv.astype(np.float64) + LARGE).astype(np.float32).astype(np.float64) - LARGE
    assert uv_texels(rounded, uv) > 1000 * UV_TOLERANCE * TEXELS


@pytest.mark.requires_gpu
def test_the_offset_moves_the_texture_after_the_scale(gpu):
    """Without relief (``basic``: the hit is the interpolated uv) the offset adds to the uv as it is, in tiles, not
    scaled by uv_scale; the face's uv range moves with it, so the silhouette test keeps the same pixels."""
    still = Renderer(scene(None, ["basic"]), gpu).render("basic", SIZE)
    moved = Renderer(scene("[0.25, 0.5]", ["basic"]), gpu).render("basic", SIZE)
    both = still.covered & moved.covered
    assert both.mean() > 0.3 and (still.covered != moved.covered).mean() < 0.01
    shift = moved.data[both][:, :2].astype(np.float64) - still.data[both][:, :2]
    assert np.abs(shift - [0.25, 0.5]).max() < 1e-5
    assert np.abs(moved.color.astype(int) - still.color.astype(int))[both].max() > 32  # the bricks moved


def clamped(offset: str):
    """The default 2x2 plane of bricks under clamp addressing, at ``offset`` (TOML)."""
    lines = f"albedo = {BRICKS}\nheight = {BRICKS}\nheight_scale = 0.06\naddress = \"clamp\"\nuv_offset = {offset}\n"
    return parse_scene(material_scene(["basic"], lines, position=(0.0, 1.6, 1.2)))


@pytest.mark.requires_gpu
def test_under_clamp_the_whole_offset_moves_the_texture_off_the_face(gpu):
    """Clamp addressing has one tile, the uv square: whole tiles of the offset count. [0.5, 0] moves the uv by half
    a tile, the half of the face beyond the square discarded; [1, 0] moves all of it off the face (with repeat
    addressing both are whole-tile-free: [1, 0] draws what [0, 0] draws)."""
    still, half, whole = (Renderer(clamped(o), gpu).render("basic", SIZE) for o in ("[0.0, 0.0]", "[0.5, 0.0]",
                                                                                    "[1.0, 0.0]"))
    assert still.covered.mean() > 0.3
    assert not whole.covered.any()
    both = still.covered & half.covered
    assert 0.3 < half.covered.sum() / still.covered.sum() < 0.7
    shift = half.data[both][:, :2].astype(np.float64) - still.data[both][:, :2]
    assert np.abs(shift - [0.5, 0.0]).max() < 1e-5
    assert (half.data[half.covered][:, 0] <= 1.0).all()


def tiled_plane(size: float, tiles: float, centre, eye, target) -> str:
    """A square plane of side ``size`` centred at ``centre`` (x, z), ``tiles`` bumps tiles across it, seen from
    ``eye`` looking at ``target``."""
    eye, target, centre = ([float(x) for x in v] for v in (eye, target, centre))
    return f"""
[scene]
techniques = ["pom"]
[camera]
position = {eye}
target = {target}
near = 1e-6
far = 10.0
[materials.m]
albedo = {{ builtin = "bumps", size = [{TEXELS}, {TEXELS}] }}
height = {{ builtin = "bumps", size = [{TEXELS}, {TEXELS}] }}
height_scale = 0.05
uv_scale = [{tiles!r}, {tiles!r}]
[[objects]]
type = "plane"
material = "m"
size = [{size!r}, {size!r}]
position = [{centre[0]}, 0.0, {centre[1]}]
"""


@pytest.mark.requires_gpu
def test_heavy_tiling_searches_at_the_fraction(gpu):
    """A 2x2 plane tiled 2^14 times, seen up close near its far corner (uv ~ 16376, where float32's spacing is an
    eighth of a texel), against the same surface drawn small: a plane of 16 tiles put where those tiles are and
    moved, with the camera, to the origin (uv ~ 0). The fragment's uv is float32 at 16376 either way; searching at
    its fraction keeps POM's fixed steps from rounding there: the median error is then the uv's own rounding."""
    tiles, small = 2.0 ** 14, 16.0
    corner = 2 * (tiles - 8) / tiles - 1  # world x = z where the heavy plane's uv is 16376 (a whole number)
    tile = 2.0 / tiles  # world units per tile
    target = np.array([corner + 4.3 * tile, 0.0, corner + 4.6 * tile])
    eye = target + np.array([0.3, 1.0, 0.9]) * 0.8 * tile
    heavy = Renderer(parse_scene(tiled_plane(2.0, tiles, (0, 0), eye, target)), gpu).render("pom", SIZE)
    moved = np.array([corner, 0.0, corner])
    side = small * tile
    near = Renderer(parse_scene(tiled_plane(side, small, (side / 2, side / 2), eye - moved, target - moved)),
                    gpu).render("pom", SIZE)
    assert heavy.covered.all() and near.covered.all()
    wrapped = (heavy.data[..., :2].astype(np.float64) - (tiles - 8) - near.data[..., :2] + 0.5) % 1.0 - 0.5
    err = np.abs(wrapped).max(axis=-1) * TEXELS
    assert np.median(err) < 0.2, np.median(err)  # 0.07 texel; 0.31 with the search at 16376
