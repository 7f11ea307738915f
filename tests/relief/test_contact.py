"""contact (techniques/contact/contact.wgsl): the GPU search is its float64 twin (tests/relief/twins.py
contact_from) ray by ray, one refine step is POM, and more sub-steps of the bracket shrink the error. Its contract
(bounds, grazing views) runs with every technique's in test_contracts.py; its comparison with relief at equal fetches
is the contact study (``wgpuviewer contact``, docs/techniques.md)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.relief.twins import contact_from
from wgpuviewer.relief.accuracy import measure, random_rays
from wgpuviewer.relief.maps import depth_range
from wgpuviewer.relief.probe import probe
from wgpuviewer.relief.reference import uv_error_texels
from wgpuviewer.textures import builtin_height

SCALE = 0.05


@pytest.mark.parametrize("name", ["bumps", "spike", "checker"])
@pytest.mark.parametrize("angle", [30.0, 75.0])
def test_contact_is_its_float64_twin(gpu, name, angle):
    """Same hits (within float32 rounding: 0.01 texel on 99 % of the rays; a ray whose sample sits on the surface to
    rounding may end one sub-step apart) and the same fetch count on nearly every ray."""
    h = builtin_height(name, (64, 64))
    uv, view = random_rays(1024, angle, seed=7)
    got = probe("contact", h, uv, view, SCALE, linear_steps=8, refine_steps=5)
    t, fetches = contact_from(h.astype(np.float64), uv, view, SCALE, 8, 5, depth_range(1.0 - h, gpu.depth_format))
    want = uv - view[:, :2] / view[:, 2:3] * SCALE * t[:, None]
    err = uv_error_texels(got.uv, want, (64, 64))
    assert np.percentile(err, 99) < 0.01, np.percentile(err, 99)
    assert (got.fetches == fetches).mean() > 0.98
    assert got.fetches.max() <= 8 + 5 and (got.layers == 8).all()


def test_one_refine_step_is_pom(gpu):
    """With one sub-step the bracket is the march's own and the secant is POM's interpolation (to float32 rounding)."""
    h = builtin_height("ridges", (64, 64))
    uv, view = random_rays(512, 50, seed=4)
    a = probe("contact", h, uv, view, SCALE, linear_steps=16, refine_steps=1)
    b = probe("pom", h, uv, view, SCALE, layers=16)
    assert np.allclose(a.uv, b.uv, atol=1e-5) and np.array_equal(a.fetches, b.fetches)


def test_refine_steps_shrink_the_error(gpu):
    """More sub-steps: a narrower final bracket, so a smaller p95, paid in fetches."""
    h = builtin_height("bumps", (128, 128))
    runs = [measure("contact", h, 60, rays=1024, linear_steps=4, refine_steps=m) for m in (1, 2, 4, 8)]
    errors = [r.error_p95 for r in runs]
    assert all(a > 1.5 * b > 0 for a, b in zip(errors, errors[1:])), errors
    fetches = [r.fetches_mean for r in runs]
    assert all(a < b for a, b in zip(fetches, fetches[1:])), fetches
