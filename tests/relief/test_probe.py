"""The GPU probe (the techniques' WGSL trace functions) against the float64 reference."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.core.errors import InputError, UserError
from wgpuviewer.relief.accuracy import measure, random_rays
from wgpuviewer.relief.probe import probe
from wgpuviewer.relief.reference import exact_hit, uv_error_texels, view_dir_from_angles
from wgpuviewer.textures import builtin_height

REAL = ("bricks", "bumps", "ridges")
HARD = ("flat0", "flat1", "spike", "step", "wall", "checker")


def height_map(name: str, size=(128, 128)) -> np.ndarray:
    return builtin_height(name, size)


@pytest.mark.parametrize("name", REAL + HARD)
@pytest.mark.parametrize("angle", [0, 30, 45, 60, 75, 80])
def test_pom_256_layers_within_half_a_texel(gpu, name, angle):
    acc = measure("pom", height_map(name), angle, height_scale=0.05, rays=1024, layers=256)
    assert acc.capped == 0.0
    assert acc.error_p95 <= 0.5, acc


@pytest.mark.parametrize("name", ["bumps", "ridges"])
def test_pom_error_falls_with_layers(gpu, name):
    errors = [measure("pom", height_map(name), 60, rays=1024, layers=n).error_p95 for n in (4, 16, 64)]
    assert errors[0] > errors[1] > errors[2], errors


def test_steep_error_within_one_layer_step(gpu):
    """Steep parallax returns the first layer below the surface: on a smooth map at most one step late."""
    h = height_map("bumps")
    layers, angle, scale = 16, 45.0, 0.05
    acc = measure("steep", h, angle, height_scale=scale, rays=1024, layers=layers)
    step_texels = np.tan(np.radians(angle)) * scale * h.shape[1] / layers
    assert acc.error_p95 <= step_texels * 1.01, (acc.error_p95, step_texels)
    assert acc.error_p95 > step_texels * 0.05  # and it is a real, measurable error


def test_offset_limited_parallax_stays_bounded(gpu):
    """Offset limiting drops the 1/V.z factor: horizontal and back-facing views give bounded offsets (flagged
    capped like every technique's: test_contracts.py)."""
    views = np.array([[1.0, 0.0, 0.0], [0.6, 0.8, 0.0], [0.0, 0.6, -0.8], [0.0, 0.0, -1.0], [1.0, 0.0, 1e-7]])
    got = probe("parallax", height_map("bumps", (64, 64)), np.full((len(views), 2), 0.3), views, 0.05,
                offset_limiting=True)
    assert np.isfinite(got.uv).all() and got.capped.all()
    assert (np.abs(got.uv - 0.3) <= 0.05 + 1e-6).all()  # |offset| <= depth * S <= S


def test_flat_maps_hit_exactly(gpu):
    uv, view = random_rays(256, 70)
    top = probe("pom", np.ones((16, 16)), uv, view, 0.05, layers=8)  # height 1: depth 0 everywhere
    assert np.allclose(top.uv, uv, atol=1e-6) and (top.depth == 0).all() and (top.fetches == 1).all()
    bottom = probe("pom", np.zeros((16, 16)), uv, view, 0.05, layers=8)  # depth 1: hit at t = 1
    expected = uv - view[:, :2] / view[:, 2:3] * 0.05
    assert np.allclose(bottom.uv, expected, atol=1e-5) and np.allclose(bottom.depth, 1.0)


def test_npot_and_single_texel_maps(gpu):
    rng = np.random.default_rng(1)
    h = np.clip(0.5 + 0.2 * np.sin(np.arange(401)[:, None] / 9.0) * np.cos(np.arange(343)[None, :] / 7.0), 0, 1)
    acc = measure("pom", h, 60, rays=1024, layers=256)
    assert acc.error_p95 <= 0.5
    one = probe("pom", np.full((1, 1), 0.25), rng.random((64, 2)), view_dir_from_angles(np.full(64, 50.0), 0.0), 0.1)
    expected_t = 0.75
    assert np.allclose(one.depth, expected_t, atol=1.5 / 16)  # default 16 layers, then interpolation
    ref = exact_hit(np.full((1, 1), 0.75), one.uv * 0 + 0.5, view_dir_from_angles(50.0, 0.0), 0.1)
    assert np.allclose(ref.t, expected_t)


@pytest.mark.parametrize("scale", [1e-4, 1.0])
def test_extreme_height_scales(gpu, scale):
    h = height_map("bumps", (64, 64))
    uv, view = random_rays(512, 60)
    got = probe("pom", h, uv, view, scale, layers=64)
    assert np.isfinite(got.uv).all()
    ref = exact_hit(1.0 - h, uv, view, scale)
    err = uv_error_texels(got.uv, ref.uv, (64, 64))
    # tiny relief: everything is within a hundredth of a texel; huge relief: POM 64 stays bounded
    assert np.percentile(err, 95) <= (0.01 if scale < 1e-3 else 3.0)


def test_clamp_addressing_matches_reference(gpu):
    h = height_map("step", (32, 32))
    uv, view = random_rays(512, 60, seed=3)
    got = probe("pom", h, uv, view, 0.05, address="clamp", layers=256)
    ref = exact_hit(1.0 - h, uv, view, 0.05, address="clamp")
    err = np.hypot(*((got.uv - ref.uv) * 32).T)  # no wrap: clamp addressing has no periodicity
    assert np.percentile(err, 95) <= 0.5


def test_probe_rejects_bad_input(gpu):
    h = np.ones((8, 8))
    with pytest.raises(InputError, match="does not trace rays"):
        probe("basic", h, [0.5, 0.5], [0, 0, 1])
    with pytest.raises(UserError, match="layers"):
        probe("pom", h, [0.5, 0.5], [0, 0, 1], layers=0)
    with pytest.raises(InputError, match="NaN"):
        probe("pom", np.full((8, 8), np.nan), [0.5, 0.5], [0, 0, 1])
    with pytest.raises(UserError, match="unknown technique"):
        probe("nope", h, [0.5, 0.5], [0, 0, 1])


@pytest.mark.parametrize("kwargs,message", [
    ({"height_scale": float("nan")}, "height_scale = nan"),
    ({"height_scale": -0.01}, "height_scale = -0.01"),
    ({"height_scale": float("inf")}, "height_scale = inf"),
    ({"height_scale": 1e30}, "from 0 to 1000"),
    ({"height": np.full((8, 8), 1.5)}, r"height: heights must lie in \[0, 1\]"),
    ({"height": np.full((8, 8), -0.5)}, r"height: heights must lie in \[0, 1\]"),
    ({"height": np.ones(8)}, r"height: expected a 2-D \(H, W\) height map, got shape \(8,\)"),
    ({"uv": np.zeros((4, 3))}, r"uv must have shape \(2,\) or \(N, 2\), got \(4, 3\)"),
    ({"view_dir": np.zeros((4, 2))}, r"view_dir must have shape \(3,\) or \(N, 3\), got \(4, 2\)"),
    ({"uv": np.zeros((4, 2)), "view_dir": np.ones((3, 3))}, "uv has 4 rows but view_dir has 3"),
    ({"uv": [np.nan, 0.5]}, "uv contains NaN/inf"),
    ({"address": "mirror"}, "address = 'mirror'"),
])
def test_probe_validates_like_exact_hit(gpu, kwargs, message):
    """Misuse is an InputError (a ValueError) naming the argument, before any GPU work; exact_hit refuses the
    same inputs (the probe also refuses a finite but float32-overflowing relief depth)."""
    args = {"height": np.full((8, 8), 0.5), "uv": [0.5, 0.5], "view_dir": [0.0, 0.6, 0.8], "height_scale": 0.05}
    args.update(kwargs)
    with pytest.raises(InputError, match=message):
        probe("pom", args["height"], args["uv"], args["view_dir"], args["height_scale"],
              address=args.get("address", "repeat"))
    if kwargs.get("height_scale") == 1e30:
        return
    with pytest.raises(ValueError):
        exact_hit(1.0 - np.asarray(args["height"], float), args["uv"], args["view_dir"], args["height_scale"],
                  address=args.get("address", "repeat"))


def test_probe_with_no_rays_returns_empty_arrays(gpu):
    got = probe("pom", np.full((8, 8), 0.5), np.zeros((0, 2)), [0.0, 0.6, 0.8])
    assert got.uv.shape == (0, 2) and got.depth.shape == got.fetches.shape == got.capped.shape == (0,)
    assert probe("maxmip", np.full((8, 8), 0.5), np.zeros((0, 2)), np.zeros((0, 3))).layers.shape == (0,)


@pytest.mark.parametrize("technique", ["pom", "maxmip"])
def test_far_from_origin_uv_is_traced_as_precisely_as_near_it(gpu, technique):
    """Repeat addressing is periodic: the probe traces the fraction of uv and adds the integer part back in
    float64, so uv ~ 1e7 (where float32 spacing is a whole texture) hits exactly where uv ~ 0.3 hits."""
    h = height_map("bumps", (64, 64))
    uv, view = random_rays(256, 60, seed=5)
    near = probe(technique, h, uv, view, 0.05)
    shift = np.array([1.0e7, -3.0e7])
    far = probe(technique, h, uv + shift, view, 0.05)
    assert far.uv.dtype == np.float64 and not far.capped.any()
    assert np.abs((far.uv - shift) - near.uv).max() < 1e-6
    ref = exact_hit(1.0 - h, uv + shift, view, 0.05)
    assert np.percentile(uv_error_texels(far.uv, ref.uv, (64, 64)), 95) <= (0.5 if technique == "pom" else 1e-3)


def test_far_from_origin_uv_with_clamp_addressing_is_flagged(gpu):
    h = height_map("bumps", (64, 64))
    got = probe("pom", h, [[0.3, 0.4], [0.3, 1e7], [-5e6, 0.5]], [0.0, 0.6, 0.8], 0.05, address="clamp")
    assert got.capped.tolist() == [False, True, True]


def test_non_finite_hits_are_flagged_capped(gpu):
    """A zero view vector has no direction: whatever the shader makes of it, it is never an unflagged NaN."""
    got = probe("pom", height_map("bumps", (16, 16)), np.full((3, 2), 0.5), [[0, 0, 0], [0, 0, 1], [1, 0, 0]], 0.05)
    bad = ~np.isfinite(got.uv).all(axis=1) | ~np.isfinite(got.depth)
    assert (got.capped | ~bad).all() and not got.capped[1]


@pytest.mark.parametrize("field, value", [("uv", np.array([[0.5 + 1j, 0.5]])), ("uv", np.array([["0.5", "0.5"]])),
                                          ("view", np.array([[0.1, 0.1, 1.0 + 0j]])), ("height_scale", True)])
def test_probe_refuses_inputs_that_are_not_real_numbers(field, value):
    args = {"uv": np.array([[0.5, 0.5]]), "view": np.array([[0.1, 0.1, 1.0]]), "height_scale": 0.05}
    args[field] = value
    with pytest.raises(InputError, match=f"probe: {field}"):
        probe("pom", np.zeros((4, 4), np.float32), args["uv"], args["view"], args["height_scale"])
