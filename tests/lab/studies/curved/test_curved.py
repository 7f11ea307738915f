"""The curved-surface study: its curved exact hit reduces to the flat float64 reference as R -> inf and wherever the
curvature cannot act (a vertical ray, a ray along a cylinder's axis), equals the analytic ray-sphere (cylinder)
intersection on a constant depth map, flags the rays lost at the silhouette, and its fitted rule and limits read
back what they are given; the smoke suite end to end; bad options refused in one line."""

from __future__ import annotations

import math

import numpy as np
import pytest

from wgpuviewer.lab.studies.curved.geometry import Surface, compare, curved_hit
from wgpuviewer.lab.studies.curved.run import EXACT, SUITES, first_order, first_order_limit, measured_limit, rule_ratios, run
from wgpuviewer.relief.accuracy import random_rays
from wgpuviewer.relief.reference import exact_hit, uv_error_texels, view_dir_from_angles
from wgpuviewer.textures import builtin_height

S = 0.05


def _depth(name: str, size=(48, 40)) -> np.ndarray:
    return 1.0 - builtin_height(name, size).astype(np.float64)


@pytest.mark.parametrize("kind", ["sphere", "cylinder"])
@pytest.mark.parametrize("name", ["bricks", "spike", "step"])
def test_an_infinite_radius_is_the_flat_exact_hit(kind, name):
    depth = _depth(name)
    for angle in (0.0, 30.0, 60.0, 80.0, 85.0):
        uv, view = random_rays(200, angle, seed=int(angle) + 7)
        flat = exact_hit(depth, uv, view, S)
        for radius, tolerance in ((math.inf, 1e-9), (1e12, 1e-8)):  # 1e12: the curvature's own ~1e-10 texel
            got = curved_hit(depth, Surface(kind, radius), uv, view, S)
            assert got.hit.all() and not got.miss.any() and not got.capped.any()
            assert uv_error_texels(got.uv, flat.uv, (48, 40)).max() < tolerance, (angle, radius)
            assert np.abs(got.t - flat.t).max() < 1e-9


@pytest.mark.parametrize("kind, azimuth", [("sphere", None), ("cylinder", 90.0)])
def test_where_the_curvature_cannot_act_the_hit_is_the_flat_one(kind, azimuth):
    """A vertical ray runs along the radius of either surface; a ray along the cylinder's axis (v) sees a straight
    line: both give the flat hit at any radius."""
    depth = _depth("bricks")
    rng = np.random.default_rng(3)
    uv = rng.random((150, 2))
    if azimuth is None:
        view = view_dir_from_angles(np.zeros(150), np.zeros(150))
    else:
        view = view_dir_from_angles(rng.uniform(10.0, 85.0, 150), np.full(150, azimuth))
    flat = exact_hit(depth, uv, view, S)
    got = curved_hit(depth, Surface(kind, 0.3), uv, view, S)
    assert got.hit.all()
    assert uv_error_texels(got.uv, flat.uv, (48, 40)).max() < 1e-9


def _analytic(kind: str, radius: float, d0: float, view: np.ndarray):
    """Ray from the entry along -V against the sphere (cylinder) of radius R - S d0: (hit, uv offset, t)."""
    down = -view
    inner = radius - S * d0
    # the curved components of q = p + R z: all three (sphere) or x and z (cylinder)
    curved = down if kind == "sphere" else down * (1.0, 0.0, 1.0)
    a = (curved ** 2).sum(axis=1)
    b = radius * view[:, 2]
    c = radius ** 2 - inner ** 2
    disc = b * b - a * c
    hit = disc >= 0
    tau = np.where(hit, (b - np.sqrt(np.where(hit, disc, 0.0))) / a, np.nan)
    p = tau[:, None] * down
    q = p + (0.0, 0.0, radius)
    if kind == "sphere":
        h = np.hypot(q[:, 0], q[:, 1])
        arc = radius * np.arctan2(h, q[:, 2])
        with np.errstate(invalid="ignore"):
            offset = np.stack([q[:, 0], q[:, 1]], axis=1) * np.where(h > 0, arc / h, 1.0)[:, None]
    else:
        offset = np.stack([radius * np.arctan2(q[:, 0], q[:, 2]), q[:, 1]], axis=1)
    return hit, offset, np.full(len(view), d0)


@pytest.mark.parametrize("kind", ["sphere", "cylinder"])
def test_a_constant_depth_map_is_a_ray_sphere_intersection(kind):
    """Depth d0 everywhere is a sphere (cylinder) of radius R - S d0: the hit is the analytic intersection, and a ray
    that passes outside it leaves the shell: a miss, flagged."""
    d0 = 0.6
    depth = np.full((16, 16), d0)
    radius = 0.4  # S/R = 0.125: grazing rays pass the inner sphere
    uv = np.random.default_rng(5).random((400, 2))
    view = view_dir_from_angles(np.repeat([0.0, 30.0, 60.0, 75.0, 80.0, 85.0, 88.0, 89.5], 50),
                                np.random.default_rng(6).random(400) * 360.0)
    hit, offset, t = _analytic(kind, radius, d0, view)
    assert hit.any() and (~hit).any()
    got = curved_hit(depth, Surface(kind, radius), uv, view, S)
    assert (got.hit == hit).all() and (got.miss == ~hit).all() and not got.capped.any()
    assert uv_error_texels(got.uv[hit], uv[hit] + offset[hit], (16, 16)).max() < 1e-9
    assert np.abs(got.t[hit] - t[hit]).max() < 1e-9
    assert np.isnan(got.uv[~hit]).all()


def test_compare_counts_the_lost_rays_apart_from_the_error():
    depth = _depth("bricks")
    uv, view = random_rays(300, 80.0, seed=2)
    result = compare(depth, Surface("sphere", S / 0.1), uv, view, S)
    lost = result.curved.miss
    assert 0 < lost.mean() < 1
    assert np.isnan(result.error[lost]).all() and np.isfinite(result.error[~lost]).all()
    assert result.flat_valid.all()


def _rows(ratios, angles, kappa=0.8, depth_texels=6.4, lost_at=None):
    return [{"heightmap": "m", "surface": "sphere", "height_scale": 0.05, "depth_texels": depth_texels,
             "s_over_r": x, "angle": a, "err_p95": kappa * first_order(a, depth_texels, x),
             "curved_miss": 0.5 if lost_at is not None and x >= lost_at else 0.0} for x in ratios for a in angles]


def test_the_rule_ratios_and_the_limits_read_back_what_they_are_given():
    rows = _rows((0.001, 0.004, 0.01, 0.05, 0.2), (30.0, 45.0, 60.0, 80.0), lost_at=0.2)
    assert rule_ratios(rows, "sphere", "m", (30.0, 60.0)) == pytest.approx((0.8, 0.8))
    assert all(math.isnan(x) for x in rule_ratios(rows, "cylinder", "m", (30.0, 60.0)))
    limit = measured_limit(rows, "sphere", 0.05, 60.0, 0.5)
    assert limit == pytest.approx(first_order_limit(60.0, 6.4, 0.5 / 0.8))  # a power law: exact between ratios
    assert measured_limit(rows, "sphere", 0.05, 30.0, 10.0) == 0.05  # the lost rays at 0.2 end it
    assert measured_limit(rows, "sphere", 0.05, 80.0, 1e-6) is None
    assert first_order(45.0, 6.4, 0.01) == pytest.approx(6.4 * 0.01 * 1.5)


def test_smoke_suite(tmp_path, gpu):
    all_rows = run("smoke", tmp_path, progress=False, command="wgpuviewer curved --suite smoke")
    suite = SUITES["smoke"]
    views = len(suite.heightmaps) * len(suite.height_scales) * len(suite.surfaces) * len(suite.ratios) \
        * len(suite.angles)
    assert len(all_rows) == views * (1 + len(suite.techniques))
    rows = [r for r in all_rows if r["tracer"] == EXACT]
    for r in all_rows:
        if r["tracer"] != EXACT:  # pom's error against the curved truth: its own, then the curvature's
            twin = next(x for x in rows if (x["angle"], x["s_over_r"]) == (r["angle"], r["s_over_r"]))
            assert r["curved_miss"] == twin["curved_miss"] and r["own_p95"] > 0 and np.isfinite(r["err_p95"])
            if twin["err_p95"] > 3 * r["own_p95"]:  # where curvature dominates, the technique inherits it
                assert r["err_p95"] > 0.5 * twin["err_p95"]
    for r in rows:
        assert r["rays"] == suite.rays and r["capped"] == 0
        assert r["both_hit"] + r["curved_miss"] == pytest.approx(1.0)
        assert 0 <= r["err_p50"] <= r["err_p95"] <= r["err_max"]
    by = {(r["angle"], r["s_over_r"]): r["err_p95"] for r in rows}
    assert by[(30.0, 0.01)] < by[(30.0, 0.1)] and by[(30.0, 0.01)] < by[(80.0, 0.01)]  # curvature and angle cost
    text = (tmp_path / "report.md").read_text()
    assert text.startswith("# Relief on curved surfaces: the tangent-plane trace against the curved exact hit\n\n"
                           "- command: `wgpuviewer curved --suite smoke`\n")
    assert "## The rule" in text and "## Limits" in text and "### `pom`, sphere, S = 0.05" in text
    assert (tmp_path / "results.csv").read_text().startswith("heightmap,size,tracer,surface,height_scale")
    for png in ("error_vs_ratio.png", "rule.png"):
        assert (tmp_path / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("argv, fragment", [
    (["--angles", "86"], "--angles '86'"),
    (["--angles", "x"], "--angles 'x'"),
    (["--ratios", "0"], "--ratios '0'"),
    (["--ratios", "0.01,0.6"], "--ratios '0.01,0.6'"),
    (["--surfaces", "torus"], "--surfaces: unknown surface 'torus'"),
    (["--rays", "0"], "--rays '0'"),
    (["--rays", "1.5"], "--rays '1.5'"),
    (["--heightmaps", "nope"], "--heightmaps: unknown height map 'nope'"),
    (["--techniques", "basic"], "--techniques: 'basic' is no ray-search technique"),
])
def test_bad_options_are_one_line_before_the_folder(tmp_path, capsys, argv, fragment):
    from wgpuviewer.cli import main

    out = tmp_path / "new"
    assert main(["curved", "--out", str(out), "--suite", "smoke", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("wgpuviewer: error: ") and fragment in err[0]
    assert not out.exists()


@pytest.mark.parametrize("kind, azimuths", [("sphere", np.linspace(0.0, 360.0, 24)), ("cylinder", [0.0, 180.0])])
def test_the_first_order_rule_on_a_constant_depth_map(kind, azimuths):
    """Depth d everywhere, S/R -> 0: the hits lie N S (S/R) d^2 (tan^3 / 2 + tan) texels apart (the shell's drop
    below the tangent plane, and the radial projection of the uv), in any direction on the sphere, across the
    cylinder's axis."""
    d0, n, ratio = 0.6, 64, 1e-4
    depth = np.full((n, n), d0)
    uv = np.random.default_rng(4).random((len(azimuths), 2))
    for angle in (30.0, 60.0, 80.0):
        view = view_dir_from_angles(np.full(len(azimuths), angle), np.asarray(azimuths))
        error = compare(depth, Surface(kind, S / ratio), uv, view, S).error
        tan = math.tan(math.radians(angle))
        assert error / (n * S * ratio * d0 ** 2 * (tan ** 3 / 2 + tan)) == pytest.approx(1.0, rel=5e-3), angle
