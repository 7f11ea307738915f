"""Grazing views, 89 degrees up to V.z just above the clamp, for the tracers that walk to the first hit of the
bilinear surface (maxmip, quadmax, distance, distance_refined, cone): never behind the float64 first hit, no false
hit where a ray passes just above a peak on a cell border, the search starting at the map's shallowest depth, and
every walk uncapped at its default step caps on every builtin map (distance and cone hand a grazing ray over to
maxmip's pyramid walk)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from wgpuviewer.relief.accuracy import random_rays
from wgpuviewer.relief.probe import probe
from wgpuviewer.relief.reference import exact_hit, uv_error_texels, view_dir_from_angles
from wgpuviewer.textures import BUILTINS, builtin_height

from .batched import probe_batches

WALKS = ("maxmip", "quadmax", "distance", "distance_refined", "cone")
SCALE = 0.05
#: Float tolerance for "never behind the first hit", in layer depth t (as tests/relief/test_contracts.py).
T_TOL = 1e-4
#: View angle with V.z just above trace.wgsl's MIN_VIEW_Z = 1e-4, below which a view is clamped and flagged.
NEAR_CLAMP = math.degrees(math.acos(1.05e-4))


def tip_rays(size: int, angle: float, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """Rays that cross a cell border next to the spike's tip (the texel centre (c, c), c = size // 2, cell coordinates)
    at P, 0.05 texel from the tip along that border, at depth D(P) - margin (D(P) = 0.05). Their azimuths make the
    bilinear depth along the ray a V with its kink at P, so P is the ray's closest approach to the surface: the ray
    passes `margin` above it (> 0: no hit there) or dips |margin| into it (< 0: the hit). Half cross the border
    y = c (P = (c + 0.05, c)), half the border x = c (P = (c, c + 0.05))."""
    c, delta = size // 2, 0.05
    across_y = np.array([60.0, 75.0, 90.0, 110.0, 125.0, 250.0, 270.0, 290.0])  # mostly along v: cross y = c
    across_x = across_y - 90.0  # mostly along u: cross x = c
    phi = np.concatenate([across_y, across_x])
    p = np.concatenate([np.tile([c + delta, c], (len(across_y), 1)), np.tile([c, c + delta], (len(across_x), 1))])
    view = view_dir_from_angles(np.full(len(phi), angle), phi)
    span = view[:, :2] / view[:, 2:3] * SCALE  # uv(t) = uv0 - t * span
    return (p + 0.5) / size + (delta - margin) * span, view


#: Margins well above float32's resolution of the ray there and well below what the former fixed root slack (1e-6
#: in t: 1e-6 times f's slope, ~R = tan(angle) S W per unit t) accepted as a hit.
TIP_MARGINS = {89.0: 4e-5, 89.9: 4e-4}


@pytest.mark.parametrize("technique", WALKS)
def test_a_ray_passing_just_above_a_peak_misses_it(gpu, technique):
    """Past a cell's border the cell's quadratic continues its patch, not the surface: a ray that passes just above
    the spike's tip on a border meets that continuation just past it. Only a root within rounding of the border
    counts (common/cell.wgsl): these rays miss the tip, and the ones that dip as far into it hit it."""
    h = builtin_height("spike", (64, 64))
    cases = [(angle, m) for angle, margin in TIP_MARGINS.items() for m in (margin, -margin)]
    batches = [tip_rays(64, angle, m) for angle, m in cases]
    for (angle, m), (uv, view), got in zip(cases, batches, probe_batches(technique, h, batches, SCALE)):
        ref = exact_hit(1.0 - h, uv, view, SCALE)
        # past a missed tip the ray may have far to go: the walks without a pyramid hand it over to maxmip's
        done = ~got.capped
        assert done.all(), (angle, m)
        assert (np.abs(got.depth - ref.t)[done] <= T_TOL).all(), (angle, m, got.depth, ref.t)
        assert (got.depth <= ref.t + T_TOL).all(), (angle, m)
        # the ray is at depth 0.05 - m at P: the dip's hit is there, a missed tip's lies beyond
        assert ((ref.t <= 0.05 - m) if m < 0 else (ref.t > 0.05)).all(), (angle, m, ref.t)


@pytest.mark.parametrize("name", list(BUILTINS))
def test_walks_are_uncapped_and_exact_at_grazing_angles(gpu, name):
    """89, 89.5 and 89.9 degrees on every builtin map (64x64): no ray capped at the default step caps, none behind the
    first hit; maxmip, distance, distance_refined and cone (these two hand a grazing ray over to maxmip's pyramid
    walk) on it to float32 precision, quadmax to its leaves' 6e-5 depth quantisation (at 89.9 degrees the ray travels
    1833 texels per unit depth: 0.11 texel)."""
    h = builtin_height(name, (64, 64))
    angles = (89.0, 89.5, 89.9)
    batches = [random_rays(512, angle, seed=int(angle * 10)) for angle in angles]
    refs = [exact_hit(1.0 - h, uv, view, SCALE) for uv, view in batches]
    for technique in WALKS:
        for angle, ref, got in zip(angles, refs, probe_batches(technique, h, batches, SCALE)):
            assert not got.capped.any(), (technique, angle)
            assert (got.depth <= ref.t + T_TOL).all(), (technique, angle)
            err = uv_error_texels(got.uv, ref.uv, (64, 64))
            quantum = 6.1e-5 * math.tan(math.radians(angle)) * SCALE * 64 if technique == "quadmax" else 0.0
            assert np.percentile(err, 99) <= 0.01 + quantum, (technique, angle, float(np.percentile(err, 99)))


@pytest.mark.parametrize("technique", WALKS)
def test_the_search_starts_at_the_maps_shallowest_depth(gpu, technique):
    """Above the map's shallowest depth a ray meets nothing, so every walk starts there: on a flat map at the floor
    a ray at 89.9 degrees or with V.z just above the clamp (tan = 9500: 30 000 texels per unit depth on this map)
    goes straight to its hit. From t = 0 each sphere or cone step would close about 1/tan of the gap to the floor,
    and the caps would stop every ray."""
    h = builtin_height("flat0", (64, 64))
    angles = (89.9, NEAR_CLAMP)
    batches = [random_rays(256, angle, seed=2) for angle in angles]
    for angle, (uv, view), got in zip(angles, batches, probe_batches(technique, h, batches, SCALE)):
        assert not got.capped.any(), angle
        span = view[:, :2] / view[:, 2:3] * SCALE
        reach = math.tan(math.radians(angle)) * SCALE * 64  # texels per unit depth
        # the hit: the floor at t = 1, to float32's resolution of t there (8 ulps: 1e-6) (quadmax's leaves hold the
        # floor up to 6.1e-5 higher)
        rounding = (6.1e-5 if technique == "quadmax" else 1e-6) * reach
        assert uv_error_texels(got.uv, uv - span, (64, 64)).max() <= 0.01 + rounding, angle
        # what is left of the ray: the depth range's slack of 2^-10 above the floor, at most 2 fetches a cell
        cells = math.ceil(2.0 ** -10 * reach * math.sqrt(2.0)) + 2
        assert got.fetches.max() <= 2 * cells, (angle, int(got.fetches.max()), cells)


@pytest.mark.parametrize("name", ("spike", "step", "wall", "checker", "bumps"))
def test_never_behind_the_first_hit_with_v_z_just_above_the_clamp(gpu, name):
    """V.z = 1.05e-4: a ray crosses a 32x32 map 300 times per unit depth. None passes the first hit (the step cap
    stops some short of it, flagged), and every result is finite."""
    h = builtin_height(name, (32, 32))
    uv, view = random_rays(64, NEAR_CLAMP, seed=4)
    ref = exact_hit(1.0 - h, uv, view, SCALE)
    for technique in WALKS:
        got = probe(technique, h, uv, view, SCALE)
        assert np.isfinite(got.uv).all() and np.isfinite(got.depth).all(), technique
        assert (got.depth <= ref.t + T_TOL).all(), (technique, float(np.max(got.depth - ref.t)))
