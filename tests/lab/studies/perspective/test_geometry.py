"""The study's quad: its coefficients reproduce the float64 ray-plane intersection at every pixel, its tilt and
offset mean what they say, and bad or extreme coefficient sets are handled (normalised or refused by name)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from wgpuviewer import camera as cam
from wgpuviewer import meshes
from wgpuviewer.core.errors import InputError
from wgpuviewer.lab.studies.perspective import geometry as g


def ray_plane_uv(quad: g.Quad) -> tuple[np.ndarray, np.ndarray]:
    """Texel (u, v) of every pixel by casting the pixel centre's ray from the eye onto the quad's plane (float64),
    independently of the coefficients: inverse view-projection, the mesh's corners through the model matrix."""
    w, h = quad.frame
    c = quad.camera
    inverse = np.linalg.inv(cam.perspective(c.fov, w / h, c.near, c.far) @ cam.look_at(c.position, c.target, c.up))
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    ndc = np.stack([(x + 0.5) / w * 2 - 1, 1 - (y + 0.5) / h * 2, np.ones_like(x), np.ones_like(x)], -1)
    far = ndc @ inverse.T
    eye = np.asarray(c.position, np.float64)
    d = far[..., :3] / far[..., 3:] - eye
    vertices = meshes.quad(*quad.size).astype(np.float64)
    model = cam.translation(quad.position) @ cam.rotation_xyz(quad.rotation)
    corner = {(u, v): (model @ [*vertices[i, :3], 1.0])[:3] for i, (u, v) in enumerate(vertices[:, 10:12])}
    origin, along_u, along_v = corner[(0, 0)], corner[(1, 0)] - corner[(0, 0)], corner[(0, 1)] - corner[(0, 0)]
    normal = np.cross(along_u, along_v)
    t = ((origin - eye) @ normal) / (d @ normal)
    hit = eye + d * t[..., None] - origin
    basis = np.stack([along_u, along_v], 1)  # (3, 2)
    local = hit @ np.linalg.pinv(basis).T  # (a, b) with hit = a * along_u + b * along_v
    texels = quad.setup.texture_size * np.asarray(quad.uv_scale)
    return local[..., 0] * texels[0], local[..., 1] * texels[1]


@pytest.mark.parametrize("setup", [
    g.Setup(span_length=64, rows=8, tilt=30.0),
    g.Setup(span_length=343, rows=5, tilt=80.0),
    g.Setup(span_length=1920, rows=4, tilt=89.9),
    g.Setup(span_length=401, rows=7, tilt=80.0, offset=1e6),
    g.Setup(span_length=1, rows=1, tilt=45.0),
])
def test_coefficients_reproduce_the_ray_plane_intersection_at_every_pixel(setup):
    quad = g.build(setup)
    ref = g.reference(quad.coefficients, quad.spans)
    u, v = ray_plane_uv(quad)
    assert ref.valid.all()
    err = np.hypot(ref.u - u, ref.v - v)
    # Both sides are float64 computations of a map with condition ~ coordinate x footprint: allow 1e-9 texel plus
    # float64's relative precision at the coordinates, amplified by the pixel's footprint at grazing angles.
    scale = np.maximum(np.abs(u), np.abs(v))
    allowed = 1e-9 + 64 * np.finfo(np.float64).eps * scale * np.maximum(ref.footprint, 1.0)
    assert (err <= allowed).all(), float((err / allowed).max())


@pytest.mark.parametrize("tilt", [30.0, 60.0, 80.0, 89.9, 95.0])
def test_tilt_is_the_angle_at_the_far_end_of_the_middle_row(tilt):
    setup = g.Setup(span_length=500, rows=9, tilt=tilt)
    quad = g.build(setup)
    normal = cam.rotation_xyz(quad.rotation)[:3, :3] @ [0.0, 0.0, 1.0]
    half = math.tan(math.radians(setup.fov_x) / 2)
    ray = np.array([((setup.span_length - 0.5) / setup.span_length * 2 - 1) * half, 0.0, -1.0])
    angle = math.degrees(math.acos(-ray @ normal / np.linalg.norm(ray)))
    assert angle == pytest.approx(tilt, abs=1e-9)
    assert quad.horizon == (tilt >= 90.0)


@pytest.mark.parametrize("offset", [0.0, 1e2, 1e6])
def test_offset_moves_the_visible_texture_coordinates_that_far_from_the_origin(offset):
    quad = g.build(g.Setup(span_length=256, rows=4, tilt=70.0, offset=offset))
    ref = g.reference(quad.coefficients, quad.spans)
    for coordinate in (ref.u, ref.v):
        # the quad's corners are float32 mesh vertices: their rounding moves the origin by ~1e-4 texel here
        assert coordinate.min() == pytest.approx(offset + g.MARGIN_TEXELS, abs=1e-3 + 1e-6 * offset)


def test_past_the_horizon_the_reference_flags_the_pixels_with_no_texel():
    quad = g.build(g.Setup(span_length=512, rows=4, tilt=100.0))
    ref = g.reference(quad.coefficients, quad.spans)
    wu, wv, q = g.numerators(quad.coefficients, quad.spans)
    assert 0.0 < ref.valid.mean() < 1.0
    assert not ref.valid[q <= 0].any()
    assert (ref.u[~ref.valid] == 0).all() and np.isinf(ref.footprint[~ref.valid]).all()
    assert np.isfinite(ref.u).all() and np.isfinite(ref.v).all()


@pytest.mark.parametrize("tilt", [89.0, 89.99, 90.0, 92.0, 100.0, 150.0])
def test_the_span_clip_keeps_only_pixels_with_a_defined_texel(tilt):
    """Inside the clip every pixel's float64 texel is defined, beyond the guard band nothing is clipped, and a span
    that sees past the horizon is clipped where it crosses."""
    rng = np.random.default_rng(int(tilt * 100))
    quad = g.build(g.Setup(span_length=3000, rows=9, tilt=tilt, offset=1e5))
    spans = g.Spans(rng.integers(-200, 200, 40), rng.integers(-3, 12, 40), 2500)
    ref = g.reference(quad.coefficients, spans)
    kept = g.inside(quad.coefficients, spans)
    assert not (kept & ~ref.valid).any()
    wu, wv, q = g.numerators(quad.coefficients, spans)
    peak = np.abs(q).max(axis=1, keepdims=True)
    safe = ref.valid & (q > 0.01 * peak) & (np.maximum(np.abs(ref.u), np.abs(ref.v)) < g.UMAX / 4)
    assert kept[safe].all()
    if tilt < 89.5:
        assert kept.all()


def test_coefficients_are_normalised_by_a_power_of_two_and_scale_free():
    quad = g.build(g.Setup(span_length=100, rows=3, tilt=60.0))
    k = quad.coefficients
    assert 0.5 <= np.abs(k).max() < 1.0
    for factor in (2.0**100, 3e30, 1e-30, 7.0):
        scaled = g.check_coefficients(k * factor)
        # a power-of-two rescale of k * factor: the same map, so the same float64 texels
        np.testing.assert_allclose(g.reference(scaled, quad.spans).u, g.reference(k, quad.spans).u, rtol=1e-14)
    np.testing.assert_array_equal(g.check_coefficients(k * 2.0**100), k)


@pytest.mark.parametrize("bad, message", [
    (np.full((3, 3), np.nan), "A1 = nan"),
    ([[1, 2, 3], [4, 5, 6], [7, 8, np.inf]], "F = inf"),
    ([[1, 2, 3], [4, 5, 6], [0, 0, 0]], "identically zero"),
    (np.zeros((2, 3)), "3x3"),
])
def test_bad_coefficients_are_refused_by_name(bad, message):
    with pytest.raises(InputError, match=message):
        g.check_coefficients(bad)


@pytest.mark.parametrize("field, value", [
    ("span_length", 0), ("span_length", g.MAX_SPAN + 1), ("rows", 0), ("tilt", float("nan")), ("tilt", 5.0),
    ("offset", -1.0), ("offset", float("inf")), ("fov_x", 0.0), ("texels_per_unit", 0.0), ("lean", 60.0),
])
def test_setup_refuses_values_out_of_range(field, value):
    with pytest.raises(InputError, match=field):
        g.Setup(**{field: value})


def test_spans_refuse_coordinates_float32_cannot_hold():
    with pytest.raises(InputError, match="2\\^24"):
        g.Spans(np.array([2**24]), np.array([0]), 10)
    with pytest.raises(InputError, match="equal"):
        g.Spans(np.array([0, 1]), np.array([0]), 10)


@pytest.mark.parametrize("setup", [g.Setup(span_length=64, rows=4, tilt=80.0), g.Setup(span_length=3840, rows=16,
                                                                                         tilt=89.9, offset=1e4)])
def test_at_footprint_gives_the_middle_pixel_the_asked_footprint_and_scales_coordinates_with_it(setup):
    for target in (0.5, 1.0, 3.0):
        scaled = g.at_footprint(setup, target)
        assert g.middle_footprint(scaled) == pytest.approx(target, rel=1e-6)
        assert replace(scaled, texels_per_unit=setup.texels_per_unit) == setup  # nothing else changes
    with pytest.raises(InputError, match="texels_per_pixel"):
        g.at_footprint(setup, 0.0)


def test_tiles_cover_the_frame_once_left_to_right_row_by_row():
    spans = g.tiles_of((256, 3), 16)
    assert spans.length == 16 and spans.count == 48
    x, y = spans.pixels()
    covered = set(zip(x.ravel().astype(int), y.ravel().astype(int)))
    assert len(covered) == x.size == 256 * 3
    assert list(spans.x0[:3]) == [0, 16, 32] and list(spans.y[15:17]) == [0, 1]
    for width in (0, 17, 512):
        with pytest.raises(InputError, match="tile width"):
            g.tiles_of((256, 3), width)
