"""Self-shadowing: the float64 reference on cases with a known answer, the GPU's hard and soft shadows against it
(the shadow probe runs the renderer's WGSL), grazing and sub-horizon lights, and the lazy shadow pipelines."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from tests.relief.scenes import material_scene
from wgpuviewer.relief import reference as ref
from wgpuviewer.relief.probe import shadow_probe
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.scene import parse_scene
from wgpuviewer.techniques import get_technique
from wgpuviewer.textures import builtin_height

#: Grid points per texel of the probe grids (the edge band below is one texel wide, in grid points).
PER_TEXEL = 2
#: The exact tracers' hard shadow may differ from the reference on at most this fraction of the grid, and only on
#: points within one texel of a reference shadow edge (the float32 trace against float64 at the tolerance's edge).
MAX_MISMATCH = 0.005
#: Mean |GPU - reference| of the soft estimate (16 samples against a dense maximum), measured <= 0.006 on these maps.
MAX_SOFT_DIFFERENCE = 0.01


def light(elevation: float, azimuth: float) -> np.ndarray:
    e, a = np.radians(elevation), np.radians(azimuth)
    return np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])


def wall_depth(size: int = 100) -> np.ndarray:
    """Floor (depth 1) with a full-height wall (depth 0) over u in [0.5, 0.6)."""
    depth = np.ones((size, size))
    depth[:, size // 2: size * 6 // 10] = 0.0
    return depth


def surface_grid(depth: np.ndarray, per_texel: int = PER_TEXEL):
    """Points on the bilinear surface on a grid of ``per_texel`` points per texel: uv (N, 2), t (N,), grid shape."""
    rows, cols = depth.shape
    gu = (np.arange(cols * per_texel) + 0.37) / (cols * per_texel)
    gv = (np.arange(rows * per_texel) + 0.37) / (rows * per_texel)
    uv = np.stack(np.meshgrid(gu, gv), -1).reshape(-1, 2)
    return uv, ref.sample_bilinear(depth, uv), (len(gv), len(gu))


def test_reference_a_wall_shadows_the_floor_in_front_of_it_up_to_its_shadow_length():
    depth = wall_depth()
    scale = 0.1
    # floor points before the wall (u < 0.5), the light beyond it (+u) at 45 degrees: the shadow is as long as the
    # wall is high, scale = 0.1 uv (the wall's full height begins at the texel centre u = 0.505); at 80 degrees and
    # scale = 0.3, 0.3 / tan(80) = 0.053 uv.
    u = np.array([0.30, 0.38, 0.42, 0.46, 0.48])
    uv = np.stack([u, np.full_like(u, 0.25)], 1)
    s45 = ref.shadow(depth, uv, np.ones(len(u)), light(45, 0), scale)
    assert s45.lit.tolist() == [True, True, False, False, False]
    s80 = ref.shadow(depth, uv, np.ones(len(u)), light(80, 0), 0.3)
    assert s80.lit.tolist() == [True, True, True, False, False]
    # behind the wall (u > 0.6) with the light on the other side (-u): the same, mirrored
    mirrored = ref.shadow(depth, np.stack([1.1 - u, u * 0 + 0.25], 1), np.ones(len(u)), light(45, 180), scale)
    assert mirrored.lit.tolist() == s45.lit.tolist()
    # soft: 1 where lit far from the shadow, 0 well inside it
    assert s45.visibility[0] == 1.0 and s45.visibility[-1] == 0.0


def test_reference_flat_maps_and_vertical_light_are_lit_and_sub_horizon_light_shadows():
    uv = np.random.default_rng(1).random((50, 2))
    for depth in (np.zeros((8, 8)), np.ones((8, 8))):
        s = ref.shadow(depth, uv, ref.sample_bilinear(depth, uv), light(30, 20), 0.05)
        assert s.lit.all() and (s.visibility == 1.0).all()
    depth = wall_depth(32)
    t = ref.sample_bilinear(depth, uv)
    assert ref.shadow(depth, uv, t, [0.0, 0.0, 1.0], 0.05).lit.all()
    below = ref.shadow(depth, uv, t, [1.0, 0.0, -0.1], 0.05)
    assert not below.lit.any() and (below.visibility == 0.0).all()
    grazing = ref.shadow(depth, uv, t, [1.0, 0.0, 1e-12], 0.05)  # too long to walk: declined, shadowed, finite
    assert not grazing.valid[t > grazing.tolerance_t].any() and np.isfinite(grazing.visibility).all()


def edge_band(lit: np.ndarray) -> np.ndarray:
    """Grid points within one texel of a change of the shadow state (periodic map)."""
    change = np.zeros_like(lit)
    for axis in (0, 1):
        step = lit != np.roll(lit, 1, axis)
        change |= step | np.roll(step, -1, axis)
    r = PER_TEXEL
    grown = ndimage.binary_dilation(np.pad(change, r, mode="wrap"), np.ones((2 * r + 1, 2 * r + 1), bool))
    return grown[r:-r, r:-r]


def hard_cases():
    spike = np.zeros((48, 40))
    spike[20, 13] = 1.0
    wall = 1.0 - wall_depth(40)
    return {"bricks": builtin_height("bricks", (64, 64)), "spike": spike, "wall": wall}


@pytest.mark.requires_gpu
@pytest.mark.parametrize("technique", ["maxmip", "quadmax"])
@pytest.mark.parametrize("elevation, azimuth", [(30, 20), (60, 200)])
def test_exact_tracers_hard_shadows_match_the_reference_but_on_edges(technique, elevation, azimuth):
    scale = 0.08
    for name, height in hard_cases().items():
        depth = 1.0 - height.astype(np.float64)
        uv, t, shape = surface_grid(depth)
        direction = light(elevation, azimuth)
        expected = ref.shadow(depth, uv, t, direction, scale)
        got = shadow_probe(technique, height, uv, t, direction, scale)
        wrong = (got.lit != expected.lit).reshape(shape)
        band = edge_band(expected.lit.reshape(shape))
        where = f"{technique} on {name} at {elevation} degrees"
        assert (~expected.lit).any() and expected.lit.any(), f"{where}: no shadow edge to test"
        assert wrong.mean() <= MAX_MISMATCH, f"{where}: {wrong.mean():.4f} of the points"
        assert not (wrong & ~band).any(), f"{where}: {int((wrong & ~band).sum())} mismatches off the edges"
        soft = np.abs(got.visibility - expected.visibility).mean()
        assert soft <= MAX_SOFT_DIFFERENCE, f"{where}: soft differs by {soft:.4f} on average"
        assert got.soft_fetches.max() == ref.SOFT_SHADOW_SAMPLES + 1
        assert not got.capped.any()


@pytest.mark.requires_gpu
def test_grazing_and_sub_horizon_lights_give_finite_flagged_shadows():
    height = builtin_height("bricks", (32, 32))
    depth = 1.0 - height.astype(np.float64)
    uv, t, _ = surface_grid(depth, 1)
    for direction, lit_allowed in (([1.0, 0.2, -0.3], False), ([1.0, 0.0, 0.0], False), ([1.0, 0.3, 1e-7], True)):
        got = shadow_probe("pom", height, uv, t, direction, 0.05)
        assert np.isfinite(got.visibility).all() and ((got.visibility >= 0) & (got.visibility <= 1)).all()
        if not lit_allowed:
            assert not got.lit.any() and (got.visibility == 0).all() and not got.capped.any()
        else:
            assert got.capped[t > 0.05].all()  # the grazing light's span was clamped: flagged


SHADOW_SCENE = """
albedo = [0.8, 0.8, 0.8]
height = {{ builtin = "bricks", size = [64, 64] }}
height_scale = 0.08
shadows = "{shadows}"
"""
LOW_LIGHT = """
[[lights]]
type = "directional"
direction = [-1.0, -0.6, -0.3]
"""


def shadow_scene(shadows: str, techniques=("pom", "basic")):
    return parse_scene(material_scene(list(techniques), SHADOW_SCENE.format(shadows=shadows), extra=LOW_LIGHT))


@pytest.mark.requires_gpu
def test_a_scene_without_shadows_builds_no_shadow_code(gpu):
    renderer = Renderer(shadow_scene("off"), gpu)
    renderer.render("pom", (48, 32))
    assert not any("shadows" in c for c in renderer.created)
    plain = renderer.module(get_technique("pom")).code
    assert "shadow_hard" not in plain and "shadow_soft" not in plain


@pytest.mark.requires_gpu
@pytest.mark.parametrize("mode", ["hard", "soft"])
def test_shadows_darken_and_cost_fetches_and_the_draw_overrides_the_material(gpu, mode):
    shadowed = Renderer(shadow_scene(mode), gpu)
    image = shadowed.render("pom", (64, 48))
    assert any(f"+shadows={mode}" in c for c in shadowed.created)
    plain = Renderer(shadow_scene("off"), gpu)
    off = plain.render("pom", (64, 48))
    assert not any("shadows" in c for c in plain.created)
    covered = off.covered & image.covered
    lit, dark = off.color[covered][:, :3].astype(int), image.color[covered][:, :3].astype(int)
    assert (dark <= lit + 1).all() and (dark < lit - 8).any(axis=1).mean() > 0.01
    assert (np.abs(image.data[covered][:, 3]) > np.abs(off.data[covered][:, 3])).mean() > 0.5  # the shadow rays
    # the draw's override: shadows off for a shadowing material, and on for a plain one
    assert np.array_equal(shadowed.render(shadowed.config("pom", shadows="off"), (64, 48)).color, off.color)
    assert np.array_equal(plain.render(plain.config("pom", shadows=mode), (64, 48)).color, image.color)
    # a technique that does not trace the relief draws no shadows and builds no shadow pipeline for it
    shadowed.render("basic", (64, 48))
    assert not any(c.startswith("pipeline:basic+") for c in shadowed.created)
