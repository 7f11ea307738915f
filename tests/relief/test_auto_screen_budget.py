"""auto's screen-space budget ``max_error_px`` (auto.wgsl auto_budget), held on synthetic pixel footprints through the
probe: the shader picks exactly the budget level of its float64 twin (autotable.fragment_budget) ray by ray, the hit
error in screen pixels stays within max_error_px where the footprint sets the budget and within max_error texels where
it does not (magnified pixels, no footprint), and minified pixels cost fewer fetches."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.core.errors import InputError
from wgpuviewer.relief.accuracy import random_rays
from wgpuviewer.relief.probe import probe
from wgpuviewer.relief.reference import exact_hit
from wgpuviewer.techniques.auto import autotable
from wgpuviewer.textures import builtin_height

SIZE = 128
SCALE = 0.05
MAX_ERROR, MAX_ERROR_PX = 0.5, 0.5
#: Texels per pixel of the synthetic footprints (isotropic scale; the anisotropic ones stretch one axis 3x): from a
#: magnified pixel to a far, minified one.
SCALES = (0.3, 1.5, 6.0, 24.0)
ANGLES = (30.0, 60.0, 80.0)


def footprint_texels(scale: float, anisotropic: bool, n: int, seed: int) -> np.ndarray:
    """(n, 4) pixels in texels (texels per pixel along screen x, then y), each rotated at random on the map."""
    rng = np.random.default_rng(seed)
    a = rng.random(n) * 2 * np.pi
    rot = np.stack([np.cos(a), np.sin(a), -np.sin(a), np.cos(a)], -1).reshape(n, 2, 2)
    stretch = np.diag([scale, scale * (3.0 if anisotropic else 1.0)])
    return (rot @ stretch).transpose(0, 2, 1).reshape(n, 4)  # rows: column x, then column y


def pixel_error(hit_uv, ref_uv, footprint: np.ndarray) -> np.ndarray:
    """Screen pixels between two hits: the texel difference through the inverse of the pixel's footprint."""
    e = (hit_uv - ref_uv) * SIZE
    j = footprint.reshape(-1, 2, 2).transpose(0, 2, 1)  # columns: screen x, screen y
    return np.linalg.norm(np.linalg.solve(j, e[:, :, None])[:, :, 0], axis=1)


@pytest.fixture(scope="module")
def measured(gpu):
    """Per (map, angle, scale, anisotropic): the rays, their footprint, the exact hits and auto's hits."""
    out = {}
    for name in ("bricks", "ridges"):
        h = builtin_height(name, (SIZE, SIZE))
        for angle in ANGLES:
            uv, view = random_rays(512, angle, seed=int(angle))
            ref = exact_hit(1.0 - h, uv, view, SCALE)
            for scale in SCALES:
                for aniso in (False, True):
                    fp = footprint_texels(scale, aniso, len(uv), seed=int(scale * 10))
                    got = probe("auto", h, uv, view, SCALE, footprint=fp / SIZE, max_error=MAX_ERROR,
                                max_error_px=MAX_ERROR_PX)
                    out[name, angle, scale, aniso] = (h, uv, view, fp, ref, got)
    return out


def test_the_shader_takes_its_twins_budget_level(measured):
    """Per ray, auto with a footprint is auto without one at max_error = the level of fragment_budget (float32 may
    round a ray at a level's edge the other way: at most 1 %)."""
    for (name, angle, scale, aniso), (h, uv, view, fp, _, got) in measured.items():
        if aniso or angle != 60.0:
            continue
        budget = autotable.fragment_budget(MAX_ERROR, MAX_ERROR_PX, fp, view)
        levels = np.array([autotable.budget_level(b) for b in budget])
        want = np.zeros_like(got.uv)
        for level in np.unique(levels):
            plain = probe("auto", h, uv, view, SCALE, max_error=float(autotable.budgets()[level]))
            want[levels == level] = plain.uv[levels == level]
        assert (np.abs(got.uv - want).max(axis=1) < 1e-6).mean() >= 0.99, (name, scale)


def test_the_error_holds_the_budget_in_pixels_or_in_texels(measured):
    """Where the footprint sets the budget (max_error_px spans more than max_error texels along the ray) the p95 hit
    error in pixels is within max_error_px; where it does not (magnified pixels) the p95 in texels is within
    max_error, the texel guarantee (in pixels that is more than max_error_px there: such a pixel spans less than a
    texel)."""
    for (name, angle, scale, aniso), (_, _, view, fp, ref, got) in measured.items():
        ok = ref.valid & ~got.capped
        by_pixels = (autotable.fragment_budget(MAX_ERROR, MAX_ERROR_PX, fp, view) > MAX_ERROR) & ok
        by_texels = ~by_pixels & ok
        if by_pixels.sum() > 50:
            px = pixel_error(got.uv[by_pixels], ref.uv[by_pixels], fp[by_pixels])
            assert np.percentile(px, 95) <= MAX_ERROR_PX, (name, angle, scale, aniso)
        if by_texels.sum() > 50:
            texels = np.linalg.norm(got.uv - ref.uv, axis=1)[by_texels] * SIZE
            assert np.percentile(texels, 95) <= MAX_ERROR, (name, angle, scale, aniso)
    assert any((autotable.fragment_budget(MAX_ERROR, MAX_ERROR_PX, m[3], m[2]) > MAX_ERROR).all()
               for m in measured.values())  # the pixel budget is what the minified cases run


def test_minified_pixels_cost_fewer_fetches_and_no_footprint_is_the_texel_budget(measured, gpu):
    for name in ("bricks", "ridges"):
        for angle in ANGLES:
            for aniso in (False, True):
                costs = [measured[name, angle, s, aniso][5].fetches.mean() for s in SCALES]
                assert all(a >= b for a, b in zip(costs, costs[1:])), (name, angle, aniso, costs)
            h, uv, view, *_ = measured[name, angle, SCALES[0], False]
            a = probe("auto", h, uv, view, SCALE, max_error=MAX_ERROR, max_error_px=MAX_ERROR_PX)
            b = probe("auto", h, uv, view, SCALE, max_error=MAX_ERROR)
            assert np.array_equal(a.uv, b.uv) and np.array_equal(a.fetches, b.fetches)
    far, near = (sum(m[5].fetches.mean() for key, m in measured.items() if key[2] == s) for s in (SCALES[-1], SCALES[0]))
    assert far < 0.9 * near, (far, near)


@pytest.mark.parametrize("footprint", [np.zeros(3), np.zeros((2, 4)), np.full(4, np.nan)])
def test_a_footprint_of_the_wrong_shape_or_not_finite_is_refused(footprint):
    uv, view = random_rays(3, 45.0)
    with pytest.raises(InputError, match="footprint"):
        probe("auto", np.zeros((8, 8)), uv, view, SCALE, footprint=footprint)
