"""3D distance maps: the plain map is the exact box distance to the sub-cell outer solid, and that solid contains the
bilinear one; the refined map's columns, bins and per-ray choice are what docs/maps.md says; no ray ever passes the
float64 exact hit with either map (random and adversarial rays, real and hard-case maps); GPU vs CPU; options; CLI."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import maptools
from maptools import cli, gpu
from maptools.kinds.distance import gpu as distance_gpu
from maptools.kinds.distance_refined import bins as rb
from maptools.kinds.distance_refined import gpu as refined_gpu
from maptools.kinds.distance_refined import visibility as rv
from maptools.registry import KINDS
from maptools.trace import sphere_trace
from maptools.volume import cpu as dist
from maptools.volume import gpu as volume_gpu
from tests.maptools.helpers import adversarial_maps, smooth_tileable
from wgpuviewer.core.compute import Compute
from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.studies.refined_distance import reliefs
from wgpuviewer.relief.reference import exact_hit, sample_bilinear, view_dir_from_angles

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
    out["plate"] = reliefs.plate(36)  # the paper's relief: deep narrow pits and slots
    out["grille"] = reliefs.grille(42)
    return out


MAPS = relief_maps()


# -- the plain map: exact box distance to the outer solid ----------------------------------------------

def brute_box_distance(depth, slices, s, k):
    """Distance from every grown voxel box to every sub-cell column, over the 3x3 nearest periodic images."""
    h, w = depth.shape
    sw, sy, dz, g = s * w, w / h, s * w / slices, dist.BOX_GROW
    tops = dist.subcell_tops(depth, k) * sw
    b, a = np.mgrid[0:h * k, 0:w * k]
    x0, y0 = 0.5 + a / k, (0.5 + b / k) * sy
    out = np.empty((slices, h, w))
    for z, j, i in itertools.product(range(slices), range(h), range(w)):
        best = np.inf
        for px, py in itertools.product((-w, 0, w), (-w, 0, w)):  # the v period is W in the metric too
            gx = np.maximum(0, np.maximum(x0 + px - (i + 1 + g), (i - g) - (x0 + px + 1 / k)))
            gy = np.maximum(0, np.maximum(y0 + py - ((j + 1) * sy + g), (j * sy - g) - (y0 + py + sy / k)))
            gz = np.maximum(0, tops - ((z + 1) * dz + g))
            best = min(best, float(np.sqrt(gx ** 2 + gy ** 2 + gz ** 2).min()))
        out[z, j, i] = best
    return out


@pytest.mark.parametrize("shape,slices,s,k", [((7, 5), 4, 0.5, 4), ((7, 5), 3, 0.3, 1), ((4, 9), 3, 0.2, 2),
                                              ((1, 1), 2, 0.1, 4), ((6, 6), 5, 1.0, 8)])
def test_plain_map_is_the_exact_box_distance(shape, slices, s, k):
    depth = RNG.random(shape)
    got = dist.box_distance(depth, slices, s, k)
    assert np.allclose(got, brute_box_distance(depth, slices, s, k), rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", ["spike", "noise_odd", "smooth_40x24", "checker", "wall"])
def test_outer_solid_contains_the_bilinear_solid(name):
    """Every point of the bilinear surface lies in its sub-cell's column: T <= D there (K = 1, 2, 4, 8)."""
    h = MAPS[name]
    rows, cols = h.shape
    depth = 1.0 - h.astype(np.float64)
    uv = np.concatenate([RNG.random((5000, 2)), (np.indices((rows, cols)).reshape(2, -1)[::-1].T + 0.5)
                         / (cols, rows)])  # random points and every texel centre
    d = sample_bilinear(depth, uv)
    for k in dist.SUBCELLS:
        tops = dist.subcell_tops(depth, k)
        a = np.floor((uv[:, 0] * cols - 0.5) * k).astype(int) % (cols * k)
        b = np.floor((uv[:, 1] * rows - 0.5) * k).astype(int) % (rows * k)
        assert (tops[b, a] <= d + 1e-12).all(), k


@pytest.mark.parametrize("name", ["spike", "smooth_40x24", "walls", "checker"])
def test_plain_value_holds_for_every_point_of_the_box(name):
    """Stored value <= distance from any point of the voxel box to any point of the bilinear solid (sampled)."""
    h = MAPS[name]
    rows, cols = h.shape
    slices, s = 6, 0.3
    vol = maptools.generate("distance", h, backend="cpu", slices=slices, height_scale=s)
    depth = 1.0 - h.astype(np.float64)
    rng = np.random.default_rng(7)
    uv = rng.random((6000, 2))
    t = sample_bilinear(depth, uv)
    t = t + (1.0 - t) * rng.random(len(t)) ** 3  # points of the solid, most near its surface
    q = np.stack([uv[:, 0] * cols, uv[:, 1] * cols, t * s * cols], axis=1)
    sy, dz = cols / rows, s * cols / slices
    for _ in range(300):
        k, j, i = rng.integers(slices), rng.integers(rows), rng.integers(cols)
        p = np.array([i + rng.random(), (j + rng.random()) * sy, (k + rng.random()) * dz])
        delta = np.abs(q - p)
        delta[:, :2] = np.minimum(delta[:, :2], cols - delta[:, :2])  # periodic in X and Y (period W)
        assert vol[k, j, i] <= np.linalg.norm(delta, axis=1).min() + 1e-9


@pytest.mark.parametrize("value", [0.0, 1.0])
def test_flat_maps_are_analytic(value):
    h = np.full((8, 12), value, np.float32)
    slices, s = 8, 0.25
    vol = maptools.generate("distance", h, backend="cpu", slices=slices, height_scale=s)
    bottom = dist.box_bottoms(slices, s, 12)
    raw = (1.0 - value) * s * 12 - bottom  # the floor at t = 1 - H below each box's bottom
    expect = np.maximum(raw - dist.STORE_MARGIN, 0)
    assert vol.shape == (slices, 8, 12) and vol.dtype == np.float32
    assert np.allclose(vol, expect[:, None, None], atol=1e-6)


def test_roll_invariance_and_layout():
    h = smooth_tileable(12, 20, 5)
    a = maptools.generate("distance", h, backend="cpu", slices=5, height_scale=0.4)
    b = maptools.generate("distance", np.roll(h, (3, 7), axis=(0, 1)), backend="cpu", slices=5, height_scale=0.4)
    assert np.allclose(np.roll(a, (3, 7), axis=(1, 2)), b, atol=1e-6)
    assert a.shape == (5, 12, 20)
    assert (np.diff(maptools.generate("distance", np.zeros((4, 4), np.float32), backend="cpu"), axis=0) <= 1e-6).all()


def test_subcells_tighten_the_plain_map():
    h = MAPS["smooth_40x24"]
    vols = [maptools.generate("distance", h, backend="cpu", slices=8, height_scale=0.3, subcells=k)
            for k in dist.SUBCELLS]
    for coarse, fine in zip(vols, vols[1:]):
        assert (fine >= coarse - 1e-6).all()
    assert (vols[-1] > vols[0] + 1e-3).mean() > 0.2


def test_round_down_never_rounds_up():
    v = np.concatenate([RNG.random(10000) * 100, [0.0, 1e-8, 65504.0, 1 / 3]])
    for dtype in (np.float16, np.float32):
        r = dist.round_down(v, dtype)
        assert r.dtype == dtype and (r.astype(np.float64) <= v).all()
        assert (np.abs(r.astype(np.float64) - v) <= np.maximum(np.abs(v) * np.finfo(dtype).eps, 1e-7)).all()


# -- the refined map: columns, bins, the tracer's choice -------------------------------------------------

def sample_wedge_rect(x0, x1, y0, y1, b, n=4000):
    """Least |p| over points p of the rectangle whose azimuth is in the bin's wedge: random ones, the rectangle's
    point nearest to 0, and dense points along the wedge's two edges (inf if none)."""
    p = np.stack([x0 + (x1 - x0) * RNG.random(n), y0 + (y1 - y0) * RNG.random(n)], axis=1)
    p = np.concatenate([p, [[np.clip(0, x0, x1), np.clip(0, y0, y1)]]])
    if not b.full:
        mid, half = 0.5 * (b.az_lo + b.az_hi), 0.5 * (b.az_hi - b.az_lo)
        off = np.abs(np.mod(np.arctan2(p[:, 1], p[:, 0]) - mid + math.pi, 2 * math.pi) - math.pi)
        t = np.linspace(0.0, 20.0, 20001)[:, None]
        edges = [t * [math.cos(a), math.sin(a)] for a in (b.az_lo, b.az_hi)]
        p = np.concatenate([p[(off <= half) | (np.hypot(*p.T) == 0)], *edges])
    p = p[(p[:, 0] >= x0) & (p[:, 0] <= x1) & (p[:, 1] >= y0) & (p[:, 1] <= y1)]
    return np.hypot(*p.T).min() if len(p) else np.inf


@pytest.mark.parametrize("sectors", [1, 2, 4, 8, 16])
def test_wedge_rho_is_the_least_length_in_the_wedge(sectors):
    for b in rb.bins(sectors, 1, 80.0):
        for _ in range(40):
            x0, y0 = RNG.uniform(-6, 6, 2)
            x1, y1 = x0 + RNG.uniform(0, 4), y0 + RNG.uniform(0, 4)
            rho = float(rb.wedge_rho(np.array([x0]), np.array([x1]), np.array([y0]), np.array([y1]), b)[0])
            sampled = sample_wedge_rect(x0, x1, y0, y1, b)
            assert rho <= sampled + 1e-12  # never above any point of the rect in the wedge
            if np.isfinite(sampled):
                assert rho >= sampled - 2e-3  # and equal to the least length, up to the sampling


@pytest.mark.parametrize("sectors,sy,reach", [(8, 1.0, 16.0), (1, 1.0, 6.0), (4, 1.7, 9.0), (2, 0.6, 5.0)])
def test_entries_cover_every_column_in_reach_once(sectors, sy, reach):
    """Each sub-cell offset within reach of the bin lies in exactly one final entry; entries never claim a rho
    above the least rho of the sub-cells they stand for."""
    k = 4
    b = rb.bins(sectors, 1, 80.0)[sectors // 2]
    e = rb.entries(b, k, sy, reach)
    ax, ay = 0.5 + dist.BOX_GROW, 0.5 * sy + dist.BOX_GROW
    covered: dict[tuple[int, int], int] = {}
    for q in np.flatnonzero(e.final):
        if e.level[q] == 0:
            subs = [(e.ox[q], e.oy[q])]
        else:
            size = 1 << (e.level[q] - 1)
            subs = [(k * (e.ox[q] + cx) + u, k * (e.oy[q] + cy) + v)
                    for cx in range(size) for cy in range(size) for u in range(k) for v in range(k)]
        sx, sy_ = np.array(subs).T
        srho = rb.wedge_rho(sx / k - ax, (sx + 1) / k + ax, sy_ / k * sy - ay, (sy_ + 1) / k * sy + ay, b)
        assert e.rho[q] <= srho.min() + 1e-12
        for s in subs:
            covered[s] = covered.get(s, 0) + 1
    assert max(covered.values()) == 1
    r = math.ceil(reach * k) + 2 * k
    oy, ox = np.mgrid[-r:r + 1, -r:r + 1]
    ox, oy = ox.ravel(), oy.ravel()
    srho = rb.wedge_rho(ox / k - ax, (ox + 1) / k + ax, oy / k * sy - ay, (oy + 1) / k * sy + ay, b)
    need = {(int(x), int(y)) for x, y, q in zip(ox, oy, srho) if q < reach}
    assert need <= set(covered)
    heads = np.flatnonzero(e.children > 0)
    assert all((e.level[q + 1:q + 1 + e.children[q]] == 0).all() for q in heads)
    outer = np.flatnonzero(e.level > 0)
    assert (np.diff(e.rho[outer]) >= 0).all()  # cells and windows sorted by rho


def test_band_edges_have_equal_cosine_ratios():
    edges = rb.band_edges(8, 80.0)
    cos = np.cos([0.0, *edges, np.radians(80.0)])
    assert len(edges) == 7 and np.allclose(cos[1:] / cos[:-1], np.cos(np.radians(80.0)) ** (1 / 8))
    assert rb.band_edges(1, 80.0) == []


def test_bins_and_the_tracers_choice():
    """volume_index picks the bin whose azimuth sector and polar band hold the ray's direction (w = (-V.x, -V.y,
    V.z)), rays steeper than max_angle the plain volume (last); the bins tile the cone."""
    bins = rb.bins(8, 4, 80.0)
    assert len(bins) == 32
    edges = np.degrees(rb.band_edges(4, 80.0))
    theta = np.concatenate([RNG.uniform(0, 89.9, 4000), edges, [0.0, 80.0, 80.001, 89.0]])
    phi = RNG.uniform(0, 360, len(theta))
    phi[-8:] = (0, 45, 90, 135, 180, 225, 270, 315)
    v = view_dir_from_angles(theta, phi)
    which = rb.volume_index(v, 8, 4, 80.0)
    w = v * [-1, -1, 1]
    polar = np.arccos(np.clip(w[:, 2], -1, 1))
    az = np.arctan2(w[:, 1], w[:, 0])
    for n in range(len(v)):
        if which[n] == len(bins):
            assert theta[n] > 80.0 - 1e-9
            continue
        b = bins[which[n]]
        assert b.polar_lo <= polar[n] <= b.polar_hi
        assert b.az_lo <= az[n] <= b.az_hi or polar[n] < 1e-9
    assert (which[theta > 80.0 + 1e-6] == len(bins)).all()


def test_refined_volumes_layout_and_floor():
    h = MAPS["smooth_40x24"]
    opts = {"slices": 6, "height_scale": 0.3}
    plain = maptools.generate("distance", h, backend="cpu", **opts)
    vol = maptools.generate("distance_refined", h, backend="cpu", sectors=4, bands=3, **opts)
    assert vol.shape == (4 * 3 + 1, 6, 24, 40) and vol.dtype == np.float16
    assert np.array_equal(vol[-1], dist.round_down(plain.astype(np.float64), np.float16))
    assert (vol[:-1].astype(np.float64) >= vol[-1].astype(np.float64)).all()  # never below the plain value
    assert (vol[:-1] > vol[-1]).mean() > 0.2  # and raised where the bins allow
    cone = maptools.generate("distance_refined", h, backend="cpu", sectors=1, bands=1, **opts)
    assert cone.shape == (2, 6, 24, 40)  # the paper's single cone, then the plain volume


# -- safety: no ray passes the exact hit ------------------------------------------------------------

def cone_rays(n, max_angle, rng):
    uv = rng.random((n, 2)) * 3 - 1  # also outside [0, 1): repeat addressing
    cos_t = 1 - rng.random(n) * (1 - np.cos(np.radians(max_angle)))  # uniform over the cone's solid angle
    return uv, view_dir_from_angles(np.degrees(np.arccos(cos_t)), rng.random(n) * 360)


def adversarial_rays(n, shape, edges, sectors, rng):
    """Rays at exactly the cone's edge and just past it, on band edges, on sector boundaries (+-1e-12 rad),
    entering at texel corners and centres, near vertical and grazing."""
    rows, cols = shape
    parts = []
    for theta in (80.0, 80.0 + 1e-9, 79.999999, 85.0, 89.0, 0.0, 1e-6, *edges):
        parts.append((rng.random((n, 2)), view_dir_from_angles(np.full(n, theta), rng.random(n) * 360)))
    # metric azimuth atan2(-V.y, -V.x) on the sector edges: V's azimuth is that + 180 degrees
    edge = np.repeat(np.arange(sectors), n // sectors + 1)[:n] * 360.0 / sectors
    for eps in (-1e-12, 0.0, 1e-12):
        theta = np.degrees(np.arccos(1 - rng.random(n) * (1 - np.cos(np.radians(80.0)))))
        parts.append((rng.random((n, 2)), view_dir_from_angles(theta, edge + 180.0 + np.degrees(eps))))
    corners = (rng.integers(0, max(cols, rows), (n, 2)) + rng.choice([0.0, 0.5], (n, 2))) / (cols, rows)
    parts.append((corners, cone_rays(n, 80.0, rng)[1]))
    return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])


TRACE_CASES = [("walls", 0.5, 16), ("noise", 0.6, 12), ("spike", 0.5, 8), ("wall", 0.4, 8), ("checker", 0.5, 8),
               ("smooth_40x24", 0.5, 12), ("step", 0.3, 10), ("flat1", 0.2, 4), ("one_texel", 0.1, 4),
               ("plate", 0.4, 12), ("grille", 0.3, 12)]
BANDS = 4


@pytest.mark.parametrize("name,s,slices", TRACE_CASES)
def test_sphere_tracing_never_tunnels(name, s, slices):
    """docs/maps.md's loop with a tiny stop radius through the plain map and the refined maps (each ray reading its
    own volume; the binned map and the paper's single cone, the visibility condition off and on): the stop point is
    never behind the float64 exact hit."""
    h = MAPS[name]
    rng = np.random.default_rng(len(name))
    plain = maptools.generate("distance", h, backend="cpu", slices=slices, height_scale=s)
    uv, v = cone_rays(1500, 89.0, rng)
    uv2, v2 = adversarial_rays(120, h.shape, np.degrees(rb.band_edges(BANDS, 80.0)), 8, rng)
    uv, v = np.concatenate([uv, uv2]), np.concatenate([v, v2])
    hit = exact_hit(1.0 - h.astype(np.float64), uv, v, s)
    assert hit.valid.all()
    maps = [("plain", plain, None)]
    for visibility in rb.VISIBILITY_CHOICES:
        for sectors, bands in ((8, BANDS), (1, 1)):
            vol = maptools.generate("distance_refined", h, backend="cpu", slices=slices, height_scale=s,
                                    sectors=sectors, bands=bands, reach=8.0, max_angle=80.0, visibility=visibility)
            maps.append((f"{sectors}x{bands} {visibility}", vol, rb.volume_index(v, sectors, bands, 80.0)))
    for label, vol, which in maps:
        t, _, _ = sphere_trace(vol, uv, v, s, stop=1e-3, max_steps=600, which=which)
        assert (t <= hit.t + 1e-9).all(), f"{label}: {int((t > hit.t + 1e-9).sum())} rays tunnelled"


def free_paths(depth, p, w, s):
    """Exact free path (metric) from points p (N, 3) along unit metric directions w (N, 3), and whether the state is
    reachable (the line from the top plane to p is free): through the float64 exact hit of the whole line."""
    rows, cols = depth.shape
    sw = s * cols
    back = p[:, 2] / w[:, 2]
    top = p - back[:, None] * w
    v = np.stack([-w[:, 0], -w[:, 1], w[:, 2]], axis=1)
    hit = exact_hit(depth, top[:, :2] / cols, v, s)
    t_p = p[:, 2] / sw
    per_t = sw / w[:, 2]  # metric length per unit of t along w
    return (hit.t - t_p) * per_t, hit.valid & (hit.t >= t_p)


@pytest.mark.parametrize("visibility", rb.VISIBILITY_CHOICES)
@pytest.mark.parametrize("name", ["walls", "spike", "checker", "smooth_40x24", "wall", "step", "noise_odd", "plate",
                                  "grille"])
def test_refined_value_never_exceeds_the_free_path(name, visibility):
    """The stored invariant itself: for random states (p above the surface, w uniform in a bin, on its edges too)
    that a ray can reach (the line from the top plane to p is free), the value of p's voxel in w's bin is at most
    the exact free path from p along w. With the visibility condition on, values are raised only where no
    reachable state needs them lower."""
    h = MAPS[name]
    rows, cols = h.shape
    slices, s = 8, 0.4
    vol = maptools.generate("distance_refined", h, backend="cpu", slices=slices, height_scale=s, sectors=8,
                            bands=BANDS, reach=8.0, max_angle=80.0, visibility=visibility).astype(np.float64)
    depth = 1.0 - h.astype(np.float64)
    rng = np.random.default_rng(3)
    n = 20000
    uv = rng.random((n, 2))
    t = sample_bilinear(depth, uv) * rng.random(n)  # above the surface: the states a ray may be in
    p = np.stack([uv[:, 0] * cols, uv[:, 1] * cols, t * s * cols], axis=1)
    bins = rb.bins(8, BANDS, 80.0)
    which = rng.integers(0, len(bins), n)
    lo = np.array([b.polar_lo for b in bins])[which]
    hi = np.array([b.polar_hi for b in bins])[which] - rb.ANGLE_SLACK
    polar = np.arccos(np.cos(lo) - rng.random(n) * (np.cos(lo) - np.cos(hi)))
    polar = np.where(rng.random(n) < 0.1, hi, polar)  # on the band's far edge too
    az_lo = np.array([b.az_lo for b in bins])[which] + rb.ANGLE_SLACK
    az = az_lo + rng.random(n) * 2 * np.pi / 8
    az = np.where(rng.random(n) < 0.1, az_lo, az)  # on the sector's edge too
    w = np.stack([np.sin(polar) * np.cos(az), np.sin(polar) * np.sin(az), np.cos(polar)], axis=1)
    free, reachable = free_paths(depth, p, w, s)
    i = np.floor(p[:, 0]).astype(int) % cols
    j = np.floor(p[:, 1] * rows / cols).astype(int) % rows
    k = np.clip(np.floor(p[:, 2] / (s * cols / slices)).astype(int), 0, slices - 1)
    value = vol[which, k, j, i]
    assert reachable.sum() > 2000
    over = reachable & (value > free + 1e-9)
    assert not over.any(), f"{int(over.sum())} states: value above the free path, worst {(value - free)[over].max()}"
    if name not in ("plate", "grille"):  # (most reachable states there are in the plate's top slice: value 0)
        assert (value[reachable] > vol[-1, k, j, i][reachable]).mean() > 0.1  # the bins do raise values


@pytest.mark.parametrize("name", ["walls", "noise"])
def test_rescaled_plain_map_stays_conservative(name):
    """A plain map built for S0, used at S with every value times min(1, S / S0) (docs/maps.md)."""
    h = MAPS[name]
    s0 = 0.4
    vol = maptools.generate("distance", h, backend="cpu", slices=12, height_scale=s0)
    rng = np.random.default_rng(3)
    for s in (0.1, 0.25, 0.8):
        uv, v = cone_rays(1000, 85.0, rng)
        hit = exact_hit(1.0 - h.astype(np.float64), uv, v, s)
        t, _, _ = sphere_trace(vol * np.float32(min(1.0, s / s0)), uv, v, s, stop=1e-3, max_steps=600)
        assert (t <= hit.t + 1e-9).all(), s


# -- the visibility condition --------------------------------------------------------------------------

@pytest.mark.parametrize("sectors,sy", [(1, 1.0), (4, 1.0), (8, 1.6), (2, 0.7)])
def test_horizon_rings_hold_every_cell_a_shifted_footprint_touches(sectors, sy):
    """For random points f of a voxel's footprint, azimuths u of the sector and distances x = n HORIZON_STEP, the
    cell holding f - x u (its offset from the voxel's own cell) is in ring n."""
    reach = 6.0
    rng = np.random.default_rng(sectors)
    for b in rb.bins(sectors, 1, 80.0):
        rings = [set(zip(ox.tolist(), oy.tolist())) for ox, oy in rv.horizon_rings(b, sy, reach)]
        assert len(rings) == rv.ring_count(reach)
        az = b.az_lo + rng.random(4000) * (b.az_hi - b.az_lo) if not b.full else rng.random(4000) * 2 * np.pi
        f = rng.random((4000, 2)) * [1.0, sy]
        for n, ring in enumerate(rings, start=1):
            x = n * rb.HORIZON_STEP
            q = f - x * np.stack([np.cos(az), np.sin(az)], axis=1)
            # cell c covers [c + 0.5, c + 1.5] x [c + 0.5, c + 1.5] sy: the texel-centre grid
            cells = set(zip(np.floor(q[:, 0] - 0.5).astype(int).tolist(),
                            np.floor(q[:, 1] / sy - 0.5).astype(int).tolist()))
            assert cells <= ring, (b, n, cells - ring)


@pytest.mark.parametrize("name", ["plate", "grille", "walls", "step"])
def test_directions_past_the_cut_cannot_reach_the_voxel(name):
    """The visibility cut's own claim: from every point of a voxel box whose cut is set, a direction of the sector
    steeper-than-allowed (polar angle just past arccot(cut), widened by the slack) meets the relief before it
    gets back to the top plane: the line from the top plane to the point is not free."""
    h = MAPS[name]
    rows, cols = h.shape
    slices, s, sectors = 8, 0.4, 4
    depth = 1.0 - h.astype(np.float64)
    cut = rv.horizon(depth, slices, s, sectors, 80.0, 8.0)
    rng = np.random.default_rng(7)
    bins = rb.bins(sectors, 1, 80.0)
    sec, k, j, i = (a[rng.permutation(a.size)[:3000]] for a in np.nonzero(cut > 0))
    assert sec.size > 100
    dz = s * cols / slices
    p = np.stack([i + rng.random(i.size), (j + rng.random(j.size)) * cols / rows,
                  (k + rng.random(k.size)) * dz], axis=1)
    polar = np.arctan2(1.0, cut[sec, k, j, i]) + 1.5 * rb.ANGLE_SLACK
    polar = np.minimum(polar + rng.random(polar.size) * (np.pi / 2 - polar) * 0.5, np.radians(89.9))
    az_lo = np.array([b.az_lo + rb.ANGLE_SLACK for b in bins])[sec]
    az = az_lo + rng.random(sec.size) * 2 * np.pi / sectors
    w = np.stack([np.sin(polar) * np.cos(az), np.sin(polar) * np.sin(az), np.cos(polar)], axis=1)
    _, reachable = free_paths(depth, p, w, s)
    assert not reachable.any(), f"{int(reachable.sum())} states past the cut are reachable"


def test_visibility_only_raises_values_and_raises_them_in_pits():
    """On: never below off (the cut only narrows a voxel's directions), and free voxels rise: most of the plate's
    (its holes are 5 texels across), some of the grille's (its 1- and 2-texel slots hold hardly a free voxel)."""
    for name, least in (("plate", 0.5), ("grille", 0.03)):
        opts = {"slices": 8, "height_scale": 0.4, "sectors": 4, "bands": 2, "max_angle": 80.0}
        off = maptools.generate("distance_refined", MAPS[name], backend="cpu", **opts).astype(np.float64)
        on = maptools.generate("distance_refined", MAPS[name], backend="cpu", visibility="on", **opts)
        on = on.astype(np.float64)
        assert (on >= off).all() and np.array_equal(on[-1], off[-1])  # the plain volume is untouched
        free = off[:-1] > 0
        assert (on[:-1] > off[:-1])[free].mean() > least, name


# -- GPU vs CPU -----------------------------------------------------------------------------------------

GPU_CASES = [("smooth_40x24", 0.3, 8, {}), ("noise_odd", 0.5, 6, {"subcells": 1}), ("spike", 0.5, 4, {}),
             ("walls", 0.5, 6, {"subcells": 8}), ("flat0", 0.2, 3, {}), ("one_texel", 0.1, 3, {}),
             ("checker", 0.4, 5, {"subcells": 2})]
REFINED_GPU = ({}, {"sectors": 1, "bands": 1}, {"sectors": 16, "bands": 6, "reach": 5.0},
               {"sectors": 1, "bands": 1, "visibility": "on"}, {"sectors": 2, "bands": 5, "visibility": "on"})


@pytest.mark.requires_gpu
@pytest.mark.parametrize("name,s,slices,extra", GPU_CASES)
def test_gpu_matches_cpu(name, s, slices, extra):
    h = MAPS[name]
    for kind, more in [("distance", {})] + [("distance_refined", r) for r in REFINED_GPU]:
        opts = {"slices": slices, "height_scale": s, **extra, **more}
        a = maptools.generate(kind, h, backend="cpu", **opts)
        b = maptools.generate(kind, h, backend="gpu", **opts)
        assert b.shape == a.shape and b.dtype == a.dtype
        c = KINDS[kind].compare(a, b, KINDS[kind].resolve(opts))
        assert c.ok, (kind, name, opts, c)


@pytest.mark.requires_gpu
def test_gpu_bakes_in_slabs_where_the_volume_is_beyond_the_storage_limit(monkeypatch):
    """A storage limit of two slices' buffers: the bakes run slab by slab (slices offset by first_slice) and give the
    volumes of the whole bake, value for value, which match the CPU references."""
    h = MAPS["smooth_40x24"]
    opts = {"slices": 5, "height_scale": 0.3, "subcells": 2}
    refined = {**opts, "sectors": 2, "bands": 6}
    whole = distance_gpu.distance(h, **opts), refined_gpu.distance_refined(h, progress=False, **refined)
    _, per_slice = volume_gpu.bake_buffers(40, 24, 2, rb.BANDS_PER_PASS)
    monkeypatch.setattr(Compute, "max_buffer", property(lambda self: 2 * per_slice))
    assert volume_gpu.slab_slices(gpu.runner(), 40, 24, 5, 2, rb.BANDS_PER_PASS) == 2  # slabs of 2, 2 and 1 slices
    slabs = distance_gpu.distance(h, **opts), refined_gpu.distance_refined(h, progress=False, **refined)
    assert np.array_equal(slabs[0], whole[0]) and np.array_equal(slabs[1], whole[1])
    for kind, options, result in (("distance", opts, slabs[0]), ("distance_refined", refined, slabs[1])):
        c = KINDS[kind].compare(maptools.generate(kind, h, backend="cpu", **options), result,
                                KINDS[kind].resolve(options))
        assert c.ok, (kind, c)


def test_fitting_subcells_follow_the_storage_limit():
    once, per_slice = volume_gpu.bake_buffers(100, 50, 4)
    assert (once, per_slice) == (100 * 50 * 16 * 4, 100 * 50 * 4 * 4)
    assert volume_gpu.bake_buffers(100, 50, 1, rb.BANDS_PER_PASS) == (100 * 50 * 4, 100 * 50 * 4 * rb.BANDS_PER_PASS)
    assert volume_gpu.fitting_subcells(100, 50, once) == 4
    assert volume_gpu.fitting_subcells(100, 50, once - 1) == 2
    assert volume_gpu.fitting_subcells(100, 50, once, most=2) == 2
    assert volume_gpu.fitting_subcells(100, 50, 100 * 50 * 4) == 1
    assert volume_gpu.fitting_subcells(100, 50, 100 * 50 * 4, lanes=rb.BANDS_PER_PASS) is None


@pytest.mark.requires_gpu
def test_a_bake_whose_single_slice_does_not_fit_names_maptools_options(monkeypatch):
    monkeypatch.setattr(Compute, "max_buffer", property(lambda self: 20000))  # the map and one slice: yes
    with pytest.raises(UserError, match=r"a 40x24 volume with 4x4 sub-cells \(its sub-cell tops\) needs a 61440-byte "
                                        r"buffer, .*; use fewer --subcells, downscale the height map or use --backend "
                                        r"cpu$"):
        maptools.generate("distance", MAPS["smooth_40x24"], backend="gpu")


# -- options, limits, CLI -----------------------------------------------------------------------------

@pytest.mark.parametrize("kind,bad,needle", [
    ("distance", {"slices": 0}, "out of range"), ("distance", {"height_scale": 0.0}, "out of range"),
    ("distance", {"height_scale": float("nan")}, "finite"), ("distance", {"slices": 2.5}, "valid int"),
    ("distance", {"subcells": 3}, "expected one of"), ("distance", {"bogus": 1}, "unknown option"),
    ("distance_refined", {"max_angle": 90.0}, "out of range"),
    ("distance_refined", {"sectors": 3}, "expected one of"), ("distance_refined", {"bands": 0}, "out of range"),
    ("distance_refined", {"bands": 17}, "out of range"), ("distance_refined", {"bands": 2.5}, "valid int"),
    ("distance_refined", {"reach": 0.5}, "out of range"), ("distance_refined", {"visibility": "yes"}, "expected one of"),
])
def test_bad_options(kind, bad, needle):
    with pytest.raises(UserError, match=needle):
        maptools.generate(kind, MAPS["spike"], backend="cpu", **bad)


def test_volume_limits():
    """Refused from the sizes alone, before any work (the CPU reference at these sizes would take hours)."""
    assert dist.MAX_VOXELS == 2048 * 2048 * 16  # a 2K map's plain volume at the default slices
    with pytest.raises(UserError, match=r"a 2048x2048x17 volume holds 71303168 values, more than the limit 67108864 "
                                        r"\(float32\); downscale the height map or use fewer --slices$"):
        maptools.generate("distance", np.zeros((2048, 2048), np.float32), backend="cpu", slices=17)
    with pytest.raises(UserError, match=r"49 volumes of 512x512x128 hold .* \(float16\); downscale the height map "
                                        r"or use fewer --slices, --sectors or --bands$"):
        maptools.generate("distance_refined", np.zeros((512, 512), np.float32), backend="cpu", slices=128,
                          sectors=16, bands=3)
    with pytest.raises(UserError, match=r"^distance_refined: 33 volumes of 2048x2048x16 hold 2214592512 values, more "
                                        r"than the limit 553648128 \(float16\); downscale the height map or use fewer "
                                        r"--slices, --sectors or --bands$"):  # the default bins at 2K
        maptools.generate("distance_refined", np.zeros((2048, 2048), np.float32), backend="cpu")
    with pytest.raises(UserError, match=r"^distance_refined: a 2048x2048x17 volume holds .*; downscale the height map "
                                        r"or use fewer --slices$"):  # few volumes: the plain volume is the limit
        maptools.generate("distance_refined", np.zeros((2048, 2048), np.float32), backend="cpu", slices=17,
                          sectors=1, bands=1)


def test_cli_generate_distance(tmp_path):
    h = smooth_tileable(12, 16, 2)
    np.save(tmp_path / "h.npy", h)
    out = tmp_path / "d.npy"
    assert cli.main(["generate", "distance", str(tmp_path / "h.npy"), "-o", str(out), "--backend", "cpu",
                     "--slices", "6", "--height-scale", "0.3", "--subcells", "2"]) == 0
    vol = np.load(out)
    assert vol.dtype == np.float32 and vol.shape == (6, 12, 16)
    assert np.array_equal(vol, maptools.generate("distance", h, backend="cpu", slices=6, height_scale=0.3,
                                                 subcells=2))
    assert cli.main(["generate", "distance_refined", str(tmp_path / "h.npy"), "-o", str(tmp_path / "r.npy"),
                     "--backend", "cpu", "--slices", "4", "--sectors", "4", "--bands", "2"]) == 0
    refined = np.load(tmp_path / "r.npy")
    assert refined.dtype == np.float16 and refined.shape == (4 * 2 + 1, 4, 12, 16)
    assert cli.main(["generate", "distance", str(tmp_path / "h.npy"), "-o", str(tmp_path / "d.png"),
                     "--backend", "cpu"]) == 2


@pytest.mark.requires_gpu
def test_cli_bench(capsys):
    assert cli.main(["bench", "--kinds", "maxmip,distance,distance_refined", "--sizes", "8", "--volume-sizes", "8",
                     "--refined-sizes", "4", "--repeat", "1"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("adapter: ") and "cpu/gpu" in out[1] and len(out) == 5
    assert cli.main(["bench", "--sizes", "x"]) == 2 and "--sizes" in capsys.readouterr().err
