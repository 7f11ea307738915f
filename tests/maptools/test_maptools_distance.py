"""3D distance maps: exactness of the EDT, conservativeness against the float64 exact hit (no ray may tunnel),
GPU vs CPU, refined >= plain, options, CLI."""

from __future__ import annotations

import itertools
import logging

import numpy as np
import pytest

import maptools
from maptools import cli
from maptools import distance as dist
from maptools.registry import KINDS
from maptools.trace import sphere_trace
from tests.maptools.helpers import adversarial_maps, smooth_tileable
from wgpuviewer.core.errors import UserError
from wgpuviewer.relief.reference import exact_hit, view_dir_from_angles

RNG = np.random.default_rng(1234)


def walls(n: int = 36, period: int = 9, thick: int = 3) -> np.ndarray:
    h = np.zeros((n, n), np.float32)
    for k in range(0, n, period):
        h[:, k:k + thick] = 1.0
        h[k:k + thick, :] = 1.0
    return h


def relief_maps() -> dict[str, np.ndarray]:
    m = adversarial_maps()
    out = {k: m[k] for k in ("spike", "step", "wall", "checker", "noise_odd", "flat0", "flat1", "one_texel")}
    out["smooth_40x24"] = smooth_tileable(24, 40, 3)
    out["walls"] = walls()
    out["noise"] = RNG.random((20, 20)).astype(np.float32)
    return out


MAPS = relief_maps()


@pytest.fixture
def no_wgpu_errors(caplog):
    caplog.set_level(logging.WARNING, logger="wgpu")
    yield
    errors = [r.getMessage() for r in caplog.records if r.name.startswith("wgpu") and r.levelno >= logging.ERROR]
    assert not errors, errors


# -- the EDT is exact for the surface it defines -------------------------------------------------------

def brute_column_edt(tops, slices, s, solid_below=True):
    h, w = tops.shape
    t = dist.layer_depths(slices)
    out = np.empty((slices, h, w))
    for k, j, i in itertools.product(range(slices), range(h), range(w)):
        best = np.inf
        for qj, qi in itertools.product(range(h), range(w)):
            dx = min(abs(qi - i), w - abs(qi - i))
            dy = min(abs(qj - j), h - abs(qj - j)) * w / h
            gap = tops[qj, qi] - t[k] if solid_below else t[k] - tops[qj, qi]
            best = min(best, dx * dx + dy * dy + (max(gap, 0.0) * s * w) ** 2)
        out[k, j, i] = np.sqrt(best)
    return out


@pytest.mark.parametrize("shape,slices,s", [((7, 5), 4, 0.5), ((4, 9), 3, 0.2), ((1, 1), 2, 0.1), ((6, 6), 5, 1.0)])
def test_column_edt_is_exact(shape, slices, s):
    tops = RNG.random(shape)
    for below in (True, False):
        assert np.allclose(dist.column_edt(tops, slices, s, below), brute_column_edt(tops, slices, s, below),
                           rtol=0, atol=1e-12)


def test_neighbourhood_wraps():
    d = np.zeros((5, 6))
    d[0, 0] = 1.0
    mx = dist.neighbourhood(d, np.maximum)
    assert mx[4, 5] == 1 and mx[1, 1] == 1 and mx[2, 2] == 0 and mx.sum() == 9


def solid_samples(depth, n, rng):
    """Random points of the bilinear solid {t >= D(u, v)} in texel-metric coordinates (X, Y, t)."""
    from wgpuviewer.relief.reference import sample_bilinear

    uv = rng.random((n, 2))
    d = sample_bilinear(depth, uv)
    t = d + (1.0 - d) * rng.random(n) ** 3  # favour points near the surface
    return uv, t


@pytest.mark.parametrize("name", ["spike", "noise_odd", "smooth_40x24", "wall", "checker"])
def test_solid_distance_is_below_distance_to_the_bilinear_solid(name):
    """d(voxel centre) <= |centre - Q| for sampled points Q of the real (bilinear) solid: S' contains it."""
    h = MAPS[name]
    rows, cols = h.shape
    depth = 1.0 - h.astype(np.float64)
    slices, s = 6, 0.3
    d = dist.solid_distance(depth, slices, s)
    uv, t = solid_samples(depth, 4000, np.random.default_rng(7))
    X, Y, Z = uv[:, 0] * cols, uv[:, 1] * cols, t * s * cols
    _, sy, sz = dist.spacing(cols, rows, slices, s)
    for k, j, i in itertools.product(range(slices), range(rows), range(cols)):
        dx = np.abs(X - (i + 0.5))
        dx = np.minimum(dx, cols - dx)
        dy = np.abs(Y - (j + 0.5) * sy)
        dy = np.minimum(dy, cols - dy)  # the v period is W in the metric
        nearest = np.sqrt(dx ** 2 + dy ** 2 + (Z - (k + 0.5) * sz) ** 2).min()
        assert d[k, j, i] <= nearest + 1e-9, (k, j, i)


@pytest.mark.parametrize("value", [0.0, 1.0])
def test_flat_maps_are_analytic(value):
    h = np.full((8, 12), value, np.float32)
    slices, s = 8, 0.25
    vol = maptools.generate("distance", h, backend="cpu", slices=slices, height_scale=s)
    t = dist.layer_depths(slices)
    raw = (0.0 * t if value == 1.0 else 1.0 - t) * s * 12  # H = 1: solid from t = 0 on; H = 0: floor at t = 1
    expect = np.maximum(raw - dist.half_diagonal(12, 8, slices, s) - dist.STORE_MARGIN, 0)
    assert vol.shape == (slices, 8, 12) and vol.dtype == np.float32
    assert np.allclose(vol, expect[:, None, None], atol=1e-6)


def test_roll_invariance_and_layout():
    h = smooth_tileable(12, 20, 5)
    a = maptools.generate("distance", h, backend="cpu", slices=5, height_scale=0.4)
    b = maptools.generate("distance", np.roll(h, (3, 7), axis=(0, 1)), backend="cpu", slices=5, height_scale=0.4)
    assert np.allclose(np.roll(a, (3, 7), axis=(1, 2)), b, atol=1e-6)
    assert a.shape == (5, 12, 20)
    assert (np.diff(maptools.generate("distance", np.zeros((4, 4), np.float32), backend="cpu"), axis=0) <= 1e-6).all()


# -- conservative tracing: no ray may step past the exact first hit ------------------------------------

def cone_rays(n, max_angle, rng, grazing=()):
    uv = rng.random((n, 2)) * 3 - 1  # also outside [0, 1): repeat addressing
    cos_t = 1 - rng.random(n) * (1 - np.cos(np.radians(max_angle)))  # uniform over the cone's solid angle
    theta = np.degrees(np.arccos(cos_t))
    theta[: len(grazing)] = grazing
    return uv, view_dir_from_angles(theta, rng.random(n) * 360)


def traced(vol, h, s, uv, v):
    hit = exact_hit(1.0 - h.astype(np.float64), uv, v, s)
    t, steps, capped = sphere_trace(vol, uv, v, s, stop=0.05, max_steps=400)
    assert hit.valid.all()
    return hit.t, t, steps, capped


TRACE_CASES = [("walls", 0.5, 16), ("noise", 0.6, 12), ("spike", 0.5, 8), ("wall", 0.4, 8), ("checker", 0.5, 8),
               ("smooth_40x24", 0.5, 12), ("step", 0.3, 10), ("flat1", 0.2, 4), ("one_texel", 0.1, 4)]


@pytest.mark.parametrize("name,s,slices", TRACE_CASES)
def test_sphere_tracing_never_tunnels(name, s, slices):
    h = MAPS[name]
    rng = np.random.default_rng(len(name))
    plain = maptools.generate("distance", h, backend="cpu", slices=slices, height_scale=s)
    refined = maptools.generate("distance_refined", h, backend="cpu", slices=slices, height_scale=s,
                                max_angle=80.0, angle_step=10.0)
    assert (refined >= plain - 1e-6).all()
    uv, v = cone_rays(1500, 80.0, rng, grazing=(80.0, 79.99, 60.0, 0.0))
    for vol in (plain, refined):
        t_hit, t, _, _ = traced(vol, h, s, uv, v)
        assert (t <= t_hit + 1e-9).all(), f"{int((t > t_hit + 1e-9).sum())} rays tunnelled"


def test_rescaled_map_stays_conservative():
    """A plain map built for S0, used at S with every value times min(1, S / S0) (docs/maps.md)."""
    h = MAPS["noise"]
    s0 = 0.4
    vol = maptools.generate("distance", h, backend="cpu", slices=12, height_scale=s0)
    rng = np.random.default_rng(3)
    for s in (0.1, 0.25, 0.8):
        uv, v = cone_rays(1000, 85.0, rng)
        t_hit, t, _, _ = traced(vol * np.float32(min(1.0, s / s0)), h, s, uv, v)
        assert (t <= t_hit + 1e-9).all(), s


def test_refined_step_counts_reported(capsys):
    """Same rays, same stop rule: mean sphere-tracing steps with distance vs distance_refined (reported)."""
    h = walls(48, 12, 3)
    s, slices = 0.5, 16
    plain = maptools.generate("distance", h, backend="cpu", slices=slices, height_scale=s)
    refined = maptools.generate("distance_refined", h, backend="cpu", slices=slices, height_scale=s,
                                max_angle=60.0, angle_step=6.0)
    uv, v = cone_rays(3000, 60.0, np.random.default_rng(11))
    rows = []
    for vol in (plain, refined):
        t_hit, t, steps, capped = traced(vol, h, s, uv, v)
        assert (t <= t_hit + 1e-9).all()
        err = (t_hit - t) * s * 48 / v[:, 2]  # along the ray, texels
        rows.append((steps.mean(), err.mean(), int(capped.sum())))
    with capsys.disabled():
        print(f"\n  walls48 S=0.5 cone 60: plain steps {rows[0][0]:.2f} err {rows[0][1]:.3f} | "
              f"refined steps {rows[1][0]:.2f} err {rows[1][1]:.3f}; "
              f"voxels raised {(refined > plain + 1e-6).mean():.3f}")
    assert rows[1][0] <= rows[0][0] + 1e-9


# -- directions --------------------------------------------------------------------------------------

@pytest.mark.parametrize("max_angle,step", [(80.0, 6.0), (45.0, 10.0), (89.0, 3.0), (5.0, 6.0)])
def test_cone_directions_cover_the_cone(max_angle, step):
    dirs, alpha = dist.cone_directions(max_angle, step)
    assert alpha <= np.radians(step) + 1e-12
    assert np.allclose(np.linalg.norm(dirs, axis=1), 1)
    assert (np.degrees(np.arccos(dirs[:, 2])) <= max_angle + 1e-9).all()
    _, v = cone_rays(20000, max_angle, np.random.default_rng(2))
    w = v * [-1, -1, 1]
    worst = np.arccos(np.clip(w @ dirs.T, -1, 1)).min(axis=1).max()
    assert worst <= alpha + 1e-9


# -- GPU vs CPU -----------------------------------------------------------------------------------------

GPU_CASES = [("smooth_40x24", 0.3, 8), ("noise_odd", 0.5, 6), ("spike", 0.5, 4), ("walls", 0.5, 6),
             ("flat0", 0.2, 3), ("one_texel", 0.1, 3), ("checker", 0.4, 5)]


@pytest.mark.requires_gpu
@pytest.mark.parametrize("name,s,slices", GPU_CASES)
def test_gpu_matches_cpu(name, s, slices):
    h = MAPS[name]
    for kind, extra in (("distance", {}), ("distance_refined", {"angle_step": 12.0})):
        opts = {"slices": slices, "height_scale": s, **extra}
        a = maptools.generate(kind, h, backend="cpu", **opts)
        b = maptools.generate(kind, h, backend="gpu", **opts)
        assert b.shape == a.shape == (slices,) + h.shape and b.dtype == np.float32
        c = KINDS[kind].compare(a, b, KINDS[kind].resolve(opts))
        assert c.ok, (kind, name, c)


# -- options, limits, CLI -----------------------------------------------------------------------------

@pytest.mark.parametrize("kind,bad,needle", [
    ("distance", {"slices": 0}, "out of range"), ("distance", {"height_scale": 0.0}, "out of range"),
    ("distance", {"height_scale": float("nan")}, "finite"), ("distance", {"slices": 2.5}, "valid int"),
    ("distance_refined", {"max_angle": 90.0}, "out of range"),
    ("distance_refined", {"max_angle": 10.0, "angle_step": 20.0}, "angle_step"),
    ("distance_refined", {"angle_step": 0.5}, "directions"), ("distance", {"bogus": 1}, "unknown option"),
])
def test_bad_options(kind, bad, needle):
    with pytest.raises(UserError, match=needle):
        maptools.generate(kind, MAPS["spike"], backend="cpu", **bad)


def test_volume_limit():
    with pytest.raises(UserError, match="voxels, more than the limit"):
        maptools.generate("distance", np.zeros((1024, 1024), np.float32), backend="cpu", slices=16)


def test_cli_generate_distance(tmp_path):
    h = smooth_tileable(12, 16, 2)
    np.save(tmp_path / "h.npy", h)
    out = tmp_path / "d.npy"
    assert cli.main(["generate", "distance", str(tmp_path / "h.npy"), "-o", str(out), "--backend", "cpu",
                     "--slices", "6", "--height-scale", "0.3"]) == 0
    vol = np.load(out)
    assert vol.dtype == np.float32 and vol.shape == (6, 12, 16)
    assert np.array_equal(vol, maptools.generate("distance", h, backend="cpu", slices=6, height_scale=0.3))
    assert cli.main(["generate", "distance_refined", str(tmp_path / "h.npy"), "-o", str(tmp_path / "r.npy"),
                     "--backend", "cpu", "--slices", "4", "--angle-step", "15"]) == 0
    assert cli.main(["generate", "distance", str(tmp_path / "h.npy"), "-o", str(tmp_path / "d.png"),
                     "--backend", "cpu"]) == 2


@pytest.mark.requires_gpu
def test_cli_bench(capsys):
    assert cli.main(["bench", "--kinds", "maxmip,distance,distance_refined", "--sizes", "8", "--volume-sizes", "8",
                     "--refined-sizes", "4", "--repeat", "1"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("adapter: ") and "cpu/gpu" in out[1] and len(out) == 5
    assert cli.main(["bench", "--sizes", "x"]) == 2 and "--sizes" in capsys.readouterr().err
