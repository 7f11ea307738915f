"""What every ray-search technique of the registry promises, tested for each one automatically (a new technique
gets these tests by being registered), at its defaults and at each of its ``contract_params``: finite results at
grazing views, flagged results for views with V.z = 0 and back-facing ones, fetch counts within the technique's
declared bound, and for exact tracers never a hit behind the float64 first hit; at the defaults, the exact tracers'
hit itself on axis-aligned rays along texel-centre lines and cell borders (where a position rounds into the
neighbouring cell). Every entry declares this coverage (contract parameters or the reason it needs none, accuracy
settings, its cost and layers view scales). Technique test files keep only their own claims."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.core.params import resolve_params
from wgpuviewer.relief.accuracy import random_rays
from wgpuviewer.relief.probe import probe
from wgpuviewer.relief.reference import exact_hit, uv_error_texels, view_dir_from_angles
from wgpuviewer.techniques import TECHNIQUES
from wgpuviewer.textures import builtin_height

from .batched import probe_batches

RAY_SEARCH = [name for name, t in TECHNIQUES.items() if t.ray_search]
EXACT = [name for name in RAY_SEARCH if TECHNIQUES[name].exact]
MAPS = ("bricks", "bumps", "flat0", "flat1", "spike", "step", "wall", "checker")
#: Float tolerance for "never behind the first hit", in layer depth t (float32 positions and depths).
T_TOL = 1e-4


def height_map(name: str) -> np.ndarray:
    return builtin_height(name, (64, 64))


def settings(names: list[str]) -> list:
    """(technique, parameter overrides) cases: each technique's defaults, then each of its contract_params."""
    return [pytest.param(name, params, id=f"{name}-" + ("-".join(f"{k}={v}" for k, v in params.items()) or "defaults"))
            for name in names for params in ({}, *TECHNIQUES[name].contract_params)]


def bound(technique: str, params: dict) -> int:
    t = TECHNIQUES[technique]
    return t.fetch_bound(resolve_params(t, params))


def test_every_ray_search_declares_its_coverage():
    for name in RAY_SEARCH:
        t = TECHNIQUES[name]
        assert t.fetch_bound is not None and t.fetch_bound(t.defaults()) >= 1, name
        assert t.cost_view_scale is not None and t.layers_view_range is not None, name
        assert t.contract_params or t.contract_exemption, f"{name}: contract_params, or a contract_exemption"
        assert t.accuracy_settings, f"{name}: accuracy_settings (`wgpuviewer accuracy` measures them)"
        for params in (*t.contract_params, *t.accuracy_settings):
            resolve_params(t, params)  # known parameters, in range
        for params in t.contract_params:  # each one differs from the defaults the tests run anyway
            assert resolve_params(t, params) != t.defaults(), (name, params)


GRAZING = (85.0, 89.0, 89.9)


@pytest.mark.parametrize(("technique", "params"), settings(RAY_SEARCH))
def test_grazing_views_are_finite_and_bounded(gpu, technique, params):
    most = bound(technique, params)
    batches = [random_rays(256, angle, seed=int(angle * 10)) for angle in GRAZING]
    for name in MAPS:
        for angle, got in zip(GRAZING, probe_batches(technique, height_map(name), batches, 0.05, **params)):
            assert np.isfinite(got.uv).all() and np.isfinite(got.depth).all(), (name, angle)
            assert ((got.depth >= 0) & (got.depth <= 1)).all(), (name, angle)
            assert got.fetches.max() <= most, (name, angle, int(got.fetches.max()), most)


@pytest.mark.parametrize(("technique", "params"), settings(RAY_SEARCH))
def test_horizontal_and_back_facing_views_are_finite_and_flagged(gpu, technique, params):
    views = np.array([[1.0, 0.0, 0.0], [0.6, 0.8, 0.0], [0.0, 0.6, -0.8], [0.0, 0.0, -1.0], [1.0, 0.0, 1e-7]])
    uv = np.full((len(views), 2), 0.3)
    for name in ("bumps", "checker", "flat1"):
        got = probe(technique, height_map(name), uv, views, 0.05, **params)
        assert np.isfinite(got.uv).all() and np.isfinite(got.depth).all(), name
        assert got.capped.all(), (name, got.capped)
    assert not exact_hit(1.0 - height_map("bumps"), uv, views, 0.05).valid.any()  # the reference declines them


@pytest.mark.parametrize(("technique", "params"), settings(RAY_SEARCH))
def test_fetches_within_the_declared_bound(gpu, technique, params):
    most = bound(technique, params)
    angles = (0.0, 45.0, 80.0)
    batches = [random_rays(512, angle, seed=7) for angle in angles]
    for name in ("bricks", "checker", "spike"):
        for angle, (uv, _), got in zip(angles, batches, probe_batches(technique, height_map(name), batches, 0.05,
                                                                      **params)):
            assert got.fetches.max() <= most, (name, angle, int(got.fetches.max()))
            # fetches are counted: a ray that fetched nothing did not move (auto's basic candidate)
            idle = got.fetches == 0
            assert np.allclose(got.uv[idle], uv[idle], atol=1e-6), (name, angle)


@pytest.mark.parametrize(("technique", "params"), settings(EXACT))
@pytest.mark.parametrize("name", MAPS)
def test_exact_tracers_never_pass_the_first_hit(gpu, technique, params, name):
    h = height_map(name)
    angles = (0.0, 30.0, 60.0, 80.0, 85.0, 89.0)
    batches = [random_rays(512, angle, seed=int(angle)) for angle in angles]
    for angle, (uv, view), got in zip(angles, batches, probe_batches(technique, h, batches, 0.05, **params)):
        ref = exact_hit(1.0 - h, uv, view, 0.05)
        ok = ref.valid
        assert (got.depth[ok] <= ref.t[ok] + T_TOL).all(), (angle, float(np.max(got.depth[ok] - ref.t[ok])))


def axis_aligned_rays(n: int, angle: float, azimuth: float) -> tuple[np.ndarray, np.ndarray]:
    """Rays along +u, +v, -u or -v (azimuth 0, 90, 180, 270: the other direction component 0) on an n-texel
    map: entries at u = (k + 0.5) / n, where the cell coordinate x = u * n - 0.5 is integral (texel centres: the
    borders of the bilinear cells, so the ray runs along one), at u = (k + 1) / n (texel corners: cell centres),
    and the same in v."""
    centres = (np.arange(n) + 0.5) / n
    corners = (np.arange(n) + 1.0) / n
    uv = np.concatenate([np.stack([centres, np.full(n, 0.37)], -1), np.stack([corners, corners[::-1]], -1),
                         np.stack([np.full(n, 0.37), centres], -1)])
    s, c = np.sin(np.radians(angle)), np.cos(np.radians(angle))
    exact = np.array({0.0: (s, 0.0, c), 90.0: (0.0, s, c), 180.0: (-s, 0.0, c), 270.0: (0.0, -s, c)}[azimuth])
    # each entry twice: the component exactly 0, and as trigonometry leaves it (about 1e-16: it survives float32,
    # so the ray drifts off the line by rounding; this is the case that once sent walks back)
    trig = view_dir_from_angles(np.full(len(uv), angle), np.full(len(uv), azimuth))
    return np.concatenate([uv, uv]), np.concatenate([np.tile(exact, (len(uv), 1)), trig])


#: UV error (texels) of an exact tracer's uncapped rays: float32 rounding only.
EXACT_TEXELS = 0.01


@pytest.mark.parametrize("technique", EXACT)  # at the defaults: the walk must finish to find the hit
@pytest.mark.parametrize("name", ("wall", "step", "spike", "checker"))
def test_exact_tracers_on_axis_aligned_rays(gpu, technique, name):
    h = height_map(name)
    cases = [(angle, azimuth) for angle in (45.0, 80.0, 85.0) for azimuth in (0.0, 90.0, 180.0, 270.0)]
    batches = [axis_aligned_rays(64, angle, azimuth) for angle, azimuth in cases]
    for (angle, azimuth), (uv, view), got in zip(cases, batches, probe_batches(technique, h, batches, 0.05)):
        ref = exact_hit(1.0 - h, uv, view, 0.05)
        ok = ref.valid & ~got.capped
        assert ok.mean() >= 0.99, (angle, azimuth, ok.mean())
        err = uv_error_texels(got.uv[ok], ref.uv[ok], h.shape)
        assert err.max() <= EXACT_TEXELS, (angle, azimuth, float(err.max()))
