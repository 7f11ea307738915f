"""Tests for wgpuviewer.relief.reference: closed-form height fields, and a dense brute-force search."""

from __future__ import annotations

import re

import numpy as np
import pytest

from wgpuviewer.core.errors import InputError
from wgpuviewer.relief.reference import (
    Hit,
    exact_hit,
    sample_bilinear,
    uv_error_texels,
    view_dir_from_angles,
)

# ----------------------------------------------------------------------------- helpers


def uv_step(view_dir, scale):
    """uv moved per unit t: uv(t) = uv0 - t * uv_step."""
    v = np.atleast_2d(view_dir)
    return v[:, :2] / v[:, 2:3] * scale


def dense_first_hit(depth, uv0, view_dir, scale, address="repeat", samples=200_001):
    """Brute force: sample f(t) = t - D(uv(t)) densely, take the first sample with f >= 0,
    then bisect against the sample before it."""
    step = uv_step(view_dir, scale)[0]
    uv0 = np.asarray(uv0, dtype=np.float64)

    def f(t):
        t = np.atleast_1d(t)
        return t - sample_bilinear(depth, uv0 - t[:, None] * step, address)

    t = np.linspace(0.0, 1.0, samples)
    above = np.flatnonzero(f(t) >= 0.0)
    k = above[0] if above.size else samples - 1
    if k == 0:
        return 0.0
    lo, hi = t[k - 1], t[k]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if f(mid)[0] >= 0.0:
            hi = mid
        else:
            lo = mid
    return hi


def smooth_map(rows, cols, seed):
    """Periodic smooth random depth in [0, 1] (sum of a few random sinusoids)."""
    rng = np.random.default_rng(seed)
    j, i = np.mgrid[0:rows, 0:cols]
    acc = np.zeros((rows, cols))
    for _ in range(6):
        kx, ky = rng.integers(-4, 5, size=2)
        acc += rng.uniform(0.2, 1.0) * np.sin(2 * np.pi * (kx * i / cols + ky * j / rows)
                                              + rng.uniform(0, 2 * np.pi))
    return (acc - acc.min()) / (acc.max() - acc.min())


def assert_matches_dense(depth, uv0s, views, scale, address="repeat"):
    hit = exact_hit(depth, uv0s, views, scale, address)
    assert hit.valid.all()
    for k in range(len(uv0s)):
        dense = dense_first_hit(depth, uv0s[k], views[k], scale, address)
        # Exact is the smallest root: never later than a crossing the dense search saw.
        assert hit.t[k] <= dense + 1e-12, (k, hit.t[k], dense)
        assert hit.t[k] == pytest.approx(dense, abs=1e-7), (k, hit.t[k], dense)
    expected_uv = np.asarray(uv0s) - hit.t[:, None] * uv_step(views, scale)
    np.testing.assert_allclose(hit.uv, expected_uv, atol=1e-12)
    return hit


def rays_towards(rng, n, target_uv, thetas, scale, spread_texels, size_wh):
    """n rays whose walk (t in [0, 1]) passes near target_uv, at the given polar angles."""
    wh = np.asarray(size_wh, dtype=np.float64)
    theta = rng.choice(thetas, n)
    phi = rng.uniform(0, 360, n)
    views = view_dir_from_angles(theta, phi)
    step = uv_step(views, scale)
    # Put the target at a random fraction of the walk, plus a sideways miss of a few texels.
    frac = rng.uniform(0.1, 0.9, n)
    miss = rng.uniform(-spread_texels, spread_texels, (n, 2)) / wh
    uv0 = np.asarray(target_uv) + frac[:, None] * step + miss
    return uv0, views


# ----------------------------------------------------------------------------- sampler


def test_sample_bilinear_hits_texel_centres_and_blends_between_them():
    rng = np.random.default_rng(1)
    depth = rng.random((5, 7))  # rows = v, cols = u
    j, i = np.mgrid[0:5, 0:7]
    centres = np.stack([(i.ravel() + 0.5) / 7, (j.ravel() + 0.5) / 5], axis=1)
    np.testing.assert_allclose(sample_bilinear(depth, centres), depth.ravel(), atol=1e-15)
    # Halfway between col 2 and 3 of row 1, then a quarter of the way down to row 2.
    uv = [(3.0) / 7, (1.5 + 0.25) / 5]
    top = 0.5 * (depth[1, 2] + depth[1, 3])
    bottom = 0.5 * (depth[2, 2] + depth[2, 3])
    assert sample_bilinear(depth, uv)[0] == pytest.approx(0.75 * top + 0.25 * bottom, abs=1e-15)


def test_sample_bilinear_repeat_vs_clamp_at_the_seam():
    depth = np.zeros((4, 8))
    depth[:, 0] = 1.0  # first column deep, last column shallow
    # u = 0 is halfway between the centres of the last and the first column.
    assert sample_bilinear(depth, [0.0, 0.5], "repeat")[0] == pytest.approx(0.5)
    assert sample_bilinear(depth, [0.0, 0.5], "clamp")[0] == pytest.approx(1.0)
    # Far outside the texture: repeat wraps, clamp holds the edge texel.
    assert sample_bilinear(depth, [-2 + 0.5 / 8, 0.5], "repeat")[0] == pytest.approx(1.0)
    assert sample_bilinear(depth, [3.0, 0.5], "clamp")[0] == pytest.approx(0.0)


# ----------------------------------------------------------------------------- closed forms


FLAT_ANGLES = [0.0, 30.0, 60.0, 85.0, 89.0, 89.9]


@pytest.mark.parametrize("d", [0.0, 0.25, 0.5, 0.73, 1.0])
@pytest.mark.parametrize("address", ["repeat", "clamp"])
def test_flat_depth_hits_at_t_equal_d(d, address):
    rng = np.random.default_rng(2)
    n = 60
    depth = np.full((16, 24), d)
    views = view_dir_from_angles(np.resize(FLAT_ANGLES, n), rng.uniform(0, 360, n))
    uv0 = rng.random((n, 2))
    hit = exact_hit(depth, uv0, views, 0.05, address)
    assert hit.valid.all()
    np.testing.assert_allclose(hit.t, d, atol=1e-12)
    np.testing.assert_allclose(hit.uv, uv0 - d * uv_step(views, 0.05), atol=1e-9)


def test_plane_field_matches_closed_form():
    # D = a + b x + c y in texel coordinates: bilinear interpolation reproduces it exactly.
    rows, cols = 50, 70
    a, b, c = 0.2, 0.008, -0.003
    j, i = np.mgrid[0:rows, 0:cols]
    depth = a + b * i + c * (j - (rows - 1))  # in [0.2, 0.2 + 0.552 + 0.147]
    rng = np.random.default_rng(3)
    n = 400
    views = view_dir_from_angles(rng.uniform(0, 80, n), rng.uniform(0, 360, n))
    uv0 = rng.uniform(0.1, 0.9, (n, 2))
    step = uv_step(views, 0.1)
    x0, y0 = uv0[:, 0] * cols - 0.5, uv0[:, 1] * rows - 0.5
    ax, ay = -step[:, 0] * cols, -step[:, 1] * rows
    # t = a + b x(t) + c (y(t) - (rows - 1))  ->  t = D(x0, y0) / (1 - b ax - c ay)
    denom = 1 - b * ax - c * ay
    t = (a + b * x0 + c * (y0 - (rows - 1))) / denom
    x1, y1 = x0 + ax * t, y0 + ay * t
    inside = (denom > 0) & (t <= 1) & (x1 >= 0) & (x1 <= cols - 1) & (y1 >= 0) & (y1 <= rows - 1)
    assert inside.sum() > 100
    hit = exact_hit(depth, uv0[inside], views[inside], 0.1, "clamp")
    np.testing.assert_allclose(hit.t, t[inside], atol=1e-9)
    np.testing.assert_allclose(hit.uv, uv0[inside] - t[inside, None] * step[inside], atol=1e-9)
    assert (hit.cells > 1).mean() > 0.5  # the walk really crossed cells


def test_saddle_field_matches_closed_form_quadratic():
    # D = 0.5 + 0.5 X Y with X, Y affine in texel coords: bilinear is exact, and along a ray
    # D is a genuine quadratic in t, so this exercises the quadratic root, not just linear ones.
    rows, cols = 40, 60
    hx, hy = (cols - 1) / 2, (rows - 1) / 2
    j, i = np.mgrid[0:rows, 0:cols]
    depth = 0.5 + 0.5 * ((i - hx) / hx) * ((j - hy) / hy)
    rng = np.random.default_rng(4)
    n = 300
    views = view_dir_from_angles(rng.uniform(20, 85, n), rng.uniform(0, 360, n))
    uv0 = rng.uniform(0.05, 0.95, (n, 2))
    scale = 0.15
    step = uv_step(views, scale)
    big_x0 = (uv0[:, 0] * cols - 0.5 - hx) / hx
    big_y0 = (uv0[:, 1] * rows - 0.5 - hy) / hy
    kx, ky = -step[:, 0] * cols / hx, -step[:, 1] * rows / hy
    expected = np.full(n, np.nan)
    for k in range(n):
        # f(t) = t - 0.5 - 0.5 (X0 + kx t)(Y0 + ky t)
        coeffs = [-0.5 * kx[k] * ky[k],
                  1 - 0.5 * (big_x0[k] * ky[k] + big_y0[k] * kx[k]),
                  -0.5 - 0.5 * big_x0[k] * big_y0[k]]
        roots = np.roots(coeffs)
        roots = roots[np.abs(roots.imag) < 1e-12].real
        roots = roots[(roots >= 0) & (roots <= 1)]
        if roots.size:
            expected[k] = roots.min()
    x1 = big_x0 + kx * expected
    y1 = big_y0 + ky * expected
    keep = np.isfinite(expected) & (np.abs(x1) <= 1) & (np.abs(y1) <= 1)
    assert keep.sum() > 100
    hit = exact_hit(depth, uv0[keep], views[keep], scale, "clamp")
    np.testing.assert_allclose(hit.t, expected[keep], atol=1e-9)


@pytest.mark.parametrize("axis", ["u", "v"])
@pytest.mark.parametrize("address", ["repeat", "clamp"])
def test_step_field_ramp_closed_form(axis, address):
    # D = 0 before texel k, 1 from texel k on: bilinear makes a one-texel ramp from centre k-1
    # to centre k. Rays start on the deep side and walk towards the shallow side.
    size, other, k = 32, 9, 12
    profile = (np.arange(size) >= k).astype(float)
    depth = np.tile(profile, (other, 1)) if axis == "u" else np.tile(profile[:, None], (1, other))
    rng = np.random.default_rng(5)
    n = 200
    theta = rng.uniform(0, 89.5, n)
    phi = rng.uniform(-60, 60, n) + (0 if axis == "u" else 90)  # V.x (or V.y) > 0: moves to -u
    views = view_dir_from_angles(theta, phi)
    along = 0 if axis == "u" else 1
    s0 = rng.uniform(k - 1, k + 8, n)  # start coordinate in texels, away from the seam
    uv0 = rng.random((n, 2))
    uv0[:, along] = (s0 + 0.5) / size
    scale = 0.1
    a = -uv_step(views, scale)[:, along] * size  # texels per unit t, negative
    # On the ramp D = s(t) - (k - 1) with s(t) = s0 + a t, so t = (s0 - k + 1) / (1 - a);
    # if that is beyond 1 the ray stays on the deep plateau and stops at t = 1.
    expected = np.minimum((s0 - k + 1) / (1 - a), 1.0)
    hit = exact_hit(depth, uv0, views, scale, address)
    np.testing.assert_allclose(hit.t, expected, atol=1e-9)
    assert (expected < 1).sum() > 50 and (expected == 1).sum() > 5


def test_repeat_and_clamp_differ_across_the_border():
    # Deep everywhere except the last column, which is shallow (depth 0). A ray leaving through
    # u = 0 meets that column's wrapped image under REPEAT, and only deep texels under CLAMP.
    cols = 16
    depth = np.ones((4, cols))
    depth[:, -1] = 0.0
    view = view_dir_from_angles(70.0, 0.0)  # V.x > 0: uv moves towards -u
    uv0 = [0.5 / cols, 0.5]  # centre of column 0, x = 0
    scale = 0.05
    a = uv_step(view, scale)[0, 0] * cols  # texels travelled towards -x per unit t
    repeat = exact_hit(depth, uv0, view, scale, "repeat")
    clamp = exact_hit(depth, uv0, view, scale, "clamp")
    # REPEAT: D(x) = 1 + x on [-1, 0] and x(t) = -a t, so t = 1 / (1 + a).
    assert repeat.t[0] == pytest.approx(1 / (1 + a), abs=1e-12)
    assert repeat.uv[0, 0] < 0  # raw uv, not wrapped back into [0, 1)
    assert clamp.t[0] == pytest.approx(1.0, abs=1e-12)
    assert clamp.uv[0, 0] == pytest.approx(uv0[0] - a / cols, abs=1e-12)


def test_repeat_is_periodic_and_clamp_is_not():
    depth = smooth_map(24, 20, seed=6)
    rng = np.random.default_rng(7)
    n = 64
    views = view_dir_from_angles(rng.uniform(0, 88, n), rng.uniform(0, 360, n))
    uv0 = rng.random((n, 2))
    shift = np.array([3.0, -2.0])
    base = exact_hit(depth, uv0, views, 0.1)
    moved = exact_hit(depth, uv0 + shift, views, 0.1)
    np.testing.assert_allclose(moved.t, base.t, atol=1e-9)
    np.testing.assert_allclose(moved.uv - shift, base.uv, atol=1e-9)
    clamp_moved = exact_hit(depth, uv0 + shift, views, 0.1, "clamp")
    assert np.abs(clamp_moved.t - base.t).max() > 0.05


# ----------------------------------------------------------------------------- brute force


def test_single_texel_spike_vs_dense_search():
    size = 32
    depth = np.ones((size, size))
    depth[13, 17] = 0.0  # one texel reaching up to the surface
    rng = np.random.default_rng(8)
    target = [(17 + 0.5) / size, (13 + 0.5) / size]
    uv0, views = rays_towards(rng, 40, target, [30, 60, 80, 85], 0.1, 1.5, (size, size))
    hit = assert_matches_dense(depth, uv0, views, 0.1)
    assert ((hit.t > 0.01) & (hit.t < 0.99)).sum() > 10  # many rays do strike the spike


def test_one_texel_wall_vs_dense_search():
    rows, cols = 20, 48
    depth = np.full((rows, cols), 0.95)
    depth[:, 30] = 0.2
    rng = np.random.default_rng(9)
    uv0, views = rays_towards(rng, 40, [(30 + 0.5) / cols, 0.5], [45, 75, 85, 89], 0.05, 2.0,
                              (cols, rows))
    hit = assert_matches_dense(depth, uv0, views, 0.05)
    assert ((hit.t > 0.2) & (hit.t < 0.94)).sum() > 10


@pytest.mark.parametrize("low, high", [(0.0, 1.0), (0.3, 0.9)])
def test_checkerboard_vs_dense_search(low, high):
    size = 16
    j, i = np.mgrid[0:size, 0:size]
    depth = np.where((i + j) % 2 == 0, low, high)
    rng = np.random.default_rng(10)
    n = 30
    views = view_dir_from_angles(rng.uniform(0, 85, n), rng.uniform(0, 360, n))
    hit = assert_matches_dense(depth, rng.random((n, 2)), views, 0.2)
    assert np.ptp(hit.t) > 0.05


def test_npot_smooth_map_vs_dense_search():
    depth = smooth_map(343, 401, seed=11)  # rows = v, cols = u
    rng = np.random.default_rng(12)
    n = 24
    views = view_dir_from_angles(rng.uniform(0, 80, n), rng.uniform(0, 360, n))
    for address in ("repeat", "clamp"):
        hit = assert_matches_dense(depth, rng.random((n, 2)), views, 0.02, address)
        # At a hit inside the walk the ray sits exactly on the surface.
        residual = hit.t - sample_bilinear(depth, hit.uv, address)
        np.testing.assert_allclose(residual[hit.t > 0], 0.0, atol=1e-9)


def test_single_row_map_vs_dense_search():
    depth = smooth_map(1, 37, seed=13)
    rng = np.random.default_rng(14)
    n = 20
    views = view_dir_from_angles(rng.uniform(0, 85, n), rng.uniform(0, 360, n))
    assert_matches_dense(depth, rng.random((n, 2)), views, 0.1)


@pytest.mark.parametrize("address", ["repeat", "clamp"])
def test_one_by_one_map(address):
    rng = np.random.default_rng(15)
    n = 30
    views = view_dir_from_angles(rng.uniform(0, 89.9, n), rng.uniform(0, 360, n))
    uv0 = rng.uniform(-2, 3, (n, 2))
    hit = exact_hit([[0.37]], uv0, views, 0.1, address)
    np.testing.assert_allclose(hit.t, 0.37, atol=1e-12)
    np.testing.assert_allclose(hit.uv, uv0 - 0.37 * uv_step(views, 0.1), atol=1e-9)


# ----------------------------------------------------------------------------- walk details


def test_cells_count_every_boundary_crossed():
    rows, cols = 12, 20
    depth = np.ones((rows, cols))  # every ray walks the whole way, t = 0 .. 1
    rng = np.random.default_rng(16)
    n = 50
    views = view_dir_from_angles(rng.uniform(0, 89, n), rng.uniform(0, 360, n))
    uv0 = rng.random((n, 2))
    hit = exact_hit(depth, uv0, views, 0.3)
    start = np.floor(uv0 * [cols, rows] - 0.5)
    end = np.floor(hit.uv * [cols, rows] - 0.5)
    np.testing.assert_array_equal(hit.cells, 1 + np.abs(end - start).sum(axis=1))
    assert hit.cells.max() > 100


def test_cells_step_both_indices_through_a_corner():
    # Along the exact diagonal from a texel centre, every boundary crossing is a cell corner:
    # 8 texels per unit t on both axes -> 8 cells, not 15 (no detour through a side cell).
    depth = np.ones((64, 64))
    hit = exact_hit(depth, [0.5 / 64, 0.5 / 64], [-1.0, -1.0, 1.0], 0.125)
    assert hit.t[0] == 1.0
    assert hit.cells[0] == 8


def test_surface_touching_the_ray_along_a_whole_cell_hits_at_entry():
    # Columns deepen by 1/8 per texel and the ray descends 1/8 per texel, starting at depth 0:
    # f(t) = t - D = 0 all the way (exactly, in binary), so the first hit is t = 0.
    depth = np.tile(np.minimum(np.arange(64) / 8, 1.0), (4, 1))
    hit = exact_hit(depth, [0.5 / 64, 0.5], [-1.0, 0.0, 1.0], 0.125)
    assert hit.t[0] == 0.0
    np.testing.assert_array_equal(hit.uv[0], [0.5 / 64, 0.5])


def test_grazing_89_9_degrees_long_walk():
    depth = smooth_map(64, 64, seed=17)
    rng = np.random.default_rng(18)
    n = 32
    views = view_dir_from_angles(89.9, rng.uniform(0, 360, n))
    uv0 = rng.random((n, 2))
    hit = exact_hit(depth, uv0, views, 0.05)
    assert hit.valid.all() and np.isfinite(hit.t).all()
    assert hit.cells.max() > 100  # ~1800 texels per unit t at this angle
    for k in range(0, n, 8):
        dense = dense_first_hit(depth, uv0[k], views[k], 0.05, samples=400_001)
        assert hit.t[k] <= dense + 1e-12
        assert hit.t[k] == pytest.approx(dense, abs=1e-7)


def test_view_scale_does_not_matter():
    depth = smooth_map(30, 30, seed=19)
    rng = np.random.default_rng(20)
    views = view_dir_from_angles(rng.uniform(0, 85, 40), rng.uniform(0, 360, 40))
    uv0 = rng.random((40, 2))
    a = exact_hit(depth, uv0, views, 0.08)
    b = exact_hit(depth, uv0, 3.7 * views, 0.08)
    np.testing.assert_allclose(b.t, a.t, atol=1e-12)


def test_broadcasting_single_view_and_single_point():
    depth = smooth_map(10, 10, seed=21)
    uv0 = np.random.default_rng(22).random((5, 2))
    view = view_dir_from_angles(50, 20)
    many = exact_hit(depth, uv0, view, 0.1)
    assert isinstance(many, Hit) and many.t.shape == (5,) and many.uv.shape == (5, 2)
    one = exact_hit(depth, uv0[3], view, 0.1)
    assert one.t.shape == (1,) and one.t[0] == many.t[3]


# ----------------------------------------------------------------------------- invalid input


def test_non_descending_views_are_invalid_nan():
    depth = np.full((8, 8), 0.5)
    views = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.6, 0.0, -0.8], [0.6, 0.0, 0.8]])
    hit = exact_hit(depth, [0.5, 0.5], views, 0.1)
    np.testing.assert_array_equal(hit.valid, [True, False, False, True])
    assert np.isnan(hit.t[1:3]).all() and np.isnan(hit.uv[1:3]).all()
    np.testing.assert_array_equal(hit.cells[1:3], 0)
    np.testing.assert_allclose(hit.t[[0, 3]], 0.5, atol=1e-12)


def test_nearly_horizontal_views_are_declined_not_walked():
    # V.z = 1e-7 would cross ~3e7 cells on a 64-texel map: past the cap, declined at once.
    depth = np.full((64, 64), 0.5)
    views = np.array([[1.0, 0.0, 1e-7], [0.0, 1.0, 1e-300], [0.6, 0.0, 0.8]])
    hit = exact_hit(depth, [0.3, 0.3], views, 0.05)
    np.testing.assert_array_equal(hit.valid, [False, False, True])
    assert np.isnan(hit.t[:2]).all() and np.isnan(hit.uv[:2]).all()


def test_max_cells_bounds_the_span_not_the_hit():
    # Span t in [0, 1] from x = 3.25 to x = 3.25 + 12.5 on one row: cells 3 .. 15 -> 13 cells.
    depth = np.full((8, 32), 0.1)
    uv0 = [(3.25 + 0.5) / 32, (2 + 0.5) / 8]
    view = [-12.5 / 32 / 0.2, 0.0, 1.0]  # S = 0.2: uv moves +12.5 texels in u over the span
    assert exact_hit(depth, uv0, view, 0.2, max_cells=13).valid[0]
    hit = exact_hit(depth, uv0, view, 0.2, max_cells=12)
    assert not hit.valid[0] and np.isnan(hit.t[0])  # declined although the hit (t = 0.1) is near


def test_exactly_grazing_angle_gives_zero_z_and_invalid():
    view = view_dir_from_angles(90.0, 30.0)
    assert view[2] == 0.0
    assert not exact_hit(np.zeros((4, 4)), [0.5, 0.5], view, 0.1).valid[0]


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_depth_raises(bad):
    depth = np.full((6, 6), 0.5)
    depth[2, 4] = bad
    with pytest.raises(ValueError, match="NaN/inf.*row 2, col 4"):
        exact_hit(depth, [0.5, 0.5], [0, 0, 1], 0.1)
    with pytest.raises(ValueError, match="NaN/inf"):
        sample_bilinear(depth, [0.5, 0.5])


@pytest.mark.parametrize("bad", [-0.01, 1.01])
def test_depth_out_of_range_raises(bad):
    depth = np.full((6, 6), 0.5)
    depth[0, 0] = bad
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        exact_hit(depth, [0.5, 0.5], [0, 0, 1], 0.1)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(view_dir=[0.1, np.nan, 1.0]), "view_dir"),
        (dict(uv=[np.inf, 0.5]), "uv"),
        (dict(height_scale=-0.1), "height_scale"),
        (dict(address="mirror"), "address"),
        (dict(uv=np.zeros((3, 2)), view_dir=np.tile([0, 0, 1.0], (2, 1))), "rows"),
        (dict(depth=np.zeros(5)), "2D"),
        (dict(max_cells=0), "max_cells"),
    ],
)
def test_bad_arguments_raise(kwargs, message):
    args = dict(depth=np.zeros((4, 4)), uv=[0.5, 0.5], view_dir=[0, 0, 1.0], height_scale=0.1)
    args.update(kwargs)
    with pytest.raises(ValueError, match=message):
        exact_hit(**args)


# ----------------------------------------------------------------------------- small helpers


def test_uv_error_texels_wraps_per_axis():
    assert uv_error_texels([0.999, 0.5], [0.001, 0.5], (100, 50))[0] == pytest.approx(0.2)
    assert uv_error_texels([0.1, 0.2], [0.3, 0.2], (100, 50))[0] == pytest.approx(20.0)
    # v wraps with H, not W: 0.99 vs 0.01 on 50 rows is 1 texel; u differs by 3 texels.
    d = uv_error_texels([[0.52, 0.99]], [[0.49, 0.01]], (100, 50))
    assert d.shape == (1,) and d[0] == pytest.approx(np.hypot(3.0, 1.0))
    # Whole periods vanish.
    assert uv_error_texels([2.25, -1.5], [0.25, 0.5], (64, 64))[0] == pytest.approx(0.0)


def test_view_dir_from_angles():
    np.testing.assert_allclose(view_dir_from_angles(0, 123), [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(view_dir_from_angles(90, 90), [0, 1, 0], atol=1e-15)
    s = np.sin(np.radians(30))
    np.testing.assert_allclose(view_dir_from_angles(30, 180), [-s, 0, np.cos(np.radians(30))],
                               atol=1e-15)
    many = view_dir_from_angles(np.linspace(0, 89.9, 7), 45.0)
    assert many.shape == (7, 3)
    np.testing.assert_allclose(np.linalg.norm(many, axis=1), 1.0, atol=1e-15)
    np.testing.assert_allclose(many[:, 0], many[:, 1], atol=1e-15)


@pytest.mark.parametrize("kwargs, message", [
    (dict(uv=np.array([0.5 + 1j, 0.5])), "uv has dtype complex128; expected real numbers"),
    (dict(uv=["0.5", "0.5"]), "uv has dtype <U3; expected real numbers"),
    (dict(view_dir=np.array([0, 0, 1], object)), "view_dir has dtype object"),
    (dict(view_dir=[True, False, True]), "view_dir has dtype bool"),
    (dict(depth=np.zeros((4, 4), complex)), "depth has dtype complex128"),
    (dict(height_scale="0.1"), "height_scale = '0.1'; expected a real number"),
    (dict(height_scale=0.1 + 0j), "height_scale = (0.1+0j); expected a real number"),
])
def test_real_numbers_only(kwargs, message):
    """Complex values would lose their imaginary part and strings would be parsed: both are refused, naming the
    argument (an InputError, which the CLIs report as one line)."""
    args = dict(depth=np.zeros((4, 4)), uv=[0.5, 0.5], view_dir=[0, 0, 1.0], height_scale=0.1)
    args.update(kwargs)
    with pytest.raises(InputError, match=re.escape(message)):
        exact_hit(**args)


def test_integer_and_other_floating_dtypes_are_real_numbers():
    hit = exact_hit(np.zeros((4, 4), np.uint8), np.array([[0, 0]], np.int64), np.array([0, 0, 1], np.float32),
                    np.float32(0.1))
    assert hit.valid[0] and hit.t[0] == 0.0
    with pytest.raises(InputError, match="theta_deg has dtype <U2"):
        view_dir_from_angles("30", 0.0)
