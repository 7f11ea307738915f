"""The quadmax tracer (wgsl/common/quadmax.wgsl) and its atlas (maps.quadmax_atlas): the packed leaves and the
children's maxima are what the tracer assumes, the tracer is never behind the float64 first hit on real and
adversarial maps (NPOT and 1x1 included), it is accurate to the leaves' quantisation, and it costs fewer fetches
than maxmip, the tracer it refines."""

from __future__ import annotations

import numpy as np
import pytest

from maptools.cache import cached_generate
from maptools.kinds.maxmip.cpu import level_sizes
from maptools.kinds.maxmip.slot import LEAF_SCALE, cell_max_height, pack_leaves, quadmax_atlas
from tests.maptools.helpers import adversarial_maps
from wgpuviewer.relief.accuracy import measure, npot_height, random_rays
from wgpuviewer.relief.probe import probe
from wgpuviewer.relief.reference import exact_hit, uv_error_texels
from wgpuviewer.textures import builtin_height

#: Float tolerance for "never behind the true first hit", in layer depth t (as the contract tests).
T_TOL = 1e-4


def unpack_leaves(words: np.ndarray) -> np.ndarray:
    """(..., 4) uint32 -> (..., 9) quantised depths, decoded bit by bit as leaf_depth in quadmax.wgsl does."""
    w = words.astype(np.uint64)
    big = w[..., 0] | (w[..., 1] << np.uint64(32))
    big2 = w[..., 2] | (w[..., 3] << np.uint64(32))
    out = []
    for k in range(9):
        bit = 14 * k
        if bit + 14 <= 64:
            q = (big >> np.uint64(bit)) & np.uint64(0x3FFF)
        elif bit >= 64:
            q = (big2 >> np.uint64(bit - 64)) & np.uint64(0x3FFF)
        else:  # straddles the two 64-bit halves
            q = ((big >> np.uint64(bit)) | (big2 << np.uint64(64 - bit))) & np.uint64(0x3FFF)
        out.append(q.astype(np.float64) / LEAF_SCALE)
    return np.stack(out, -1)


@pytest.mark.parametrize("name", ["smooth_343x401", "noise_odd", "one_texel", "spike", "flat1", "bits16"])
def test_leaves_hold_the_block_depths_rounded_towards_the_top(name):
    depth = 1.0 - adversarial_maps()[name].astype(np.float64)
    h, w = depth.shape
    got = unpack_leaves(pack_leaves(depth))
    assert got.shape == ((h + 1) // 2, (w + 1) // 2, 9)
    for k in range(9):
        b, a = divmod(k, 3)
        want = depth[np.ix_((np.arange(got.shape[0]) * 2 + b) % h, (np.arange(got.shape[1]) * 2 + a) % w)]
        # float32 decoding on the GPU cannot push a value past the true depth
        assert (got[..., k].astype(np.float32) <= want).all()
        assert (want - got[..., k] < 1.0 / LEAF_SCALE + 1e-6).all()


@pytest.mark.parametrize("shape", [(401, 343), (17, 9), (1, 1), (2, 2), (64, 64)])
def test_quad_texels_bound_their_childrens_cells(shape):
    """Child c of node P at level m (the quad texel's channel c) is >= every cell height of that child's span."""
    rng = np.random.default_rng(shape[0])
    depth = rng.random(shape)
    cells = cell_max_height(depth)
    levels = cached_generate("maxmip", cells, backend="cpu")
    atlas = quadmax_atlas(depth, levels)
    sizes = level_sizes(*shape) + [(1, 1)] * (len(level_sizes(*shape)) < 2)
    row = sizes[1][0]  # leaves first
    for m in range(2, len(sizes)):
        ph, pw = sizes[m]
        quad = atlas[row:row + ph, :pw].view(np.float32)
        row += ph
        for c, (dy, dx) in enumerate(((0, 0), (0, 1), (1, 0), (1, 1))):
            for j in range(ph):
                for i in range(pw):
                    cy, cx = 2 * j + dy, 2 * i + dx
                    if cy >= sizes[m - 1][0] or cx >= sizes[m - 1][1]:
                        continue  # no such child: the walk never visits it
                    s = 1 << (m - 1)
                    span = cells[cy * s:(cy + 1) * s, cx * s:(cx + 1) * s]
                    assert quad[j, i, c] >= span.max(), (m, j, i, c)
    assert row == atlas.shape[0]


MAPS = ("bricks", "bumps", "ridges", "flat0", "flat1", "spike", "step", "wall", "checker")


ANGLES = (0, 30, 60, 80, 85, 89, 89.9)


@pytest.mark.parametrize("name", MAPS)
def test_never_behind_the_first_hit_and_accurate(gpu, name):
    h = builtin_height(name, (64, 64))
    rays = [random_rays(512, angle, seed=int(angle)) for angle in ANGLES]
    uv, view = np.concatenate([r[0] for r in rays]), np.concatenate([r[1] for r in rays])
    got = probe("quadmax", h, uv, view, 0.05)
    ref = exact_hit(1.0 - h, uv, view, 0.05)
    for i, angle in enumerate(ANGLES):
        part = slice(512 * i, 512 * (i + 1))
        ok = ref.valid[part]
        depth, t = got.depth[part][ok], ref.t[part][ok]
        assert (depth <= t + T_TOL).all(), (angle, float(np.max(depth - t)))
        if angle <= 89:
            assert not got.capped[part][ok].any(), angle
            err = uv_error_texels(got.uv[part][ok], ref.uv[part][ok], (64, 64))
            assert np.percentile(err, 99) <= 0.02, (angle, float(np.percentile(err, 99)))


@pytest.mark.parametrize("height", [npot_height(), np.full((1, 1), 0.25), adversarial_maps()["noise_odd"]],
                         ids=["npot_343x401", "1x1", "noise_17x9"])
def test_npot_odd_and_single_texel_maps(gpu, height):
    h = np.asarray(height, np.float64)
    rays = [random_rays(1024, angle, seed=3) for angle in (0, 45, 80, 89)]
    uv, view = np.concatenate([r[0] for r in rays]), np.concatenate([r[1] for r in rays])
    got = probe("quadmax", h, uv, view, 0.1)
    ref = exact_hit(1.0 - h, uv, view, 0.1)
    assert (got.depth <= ref.t + T_TOL).all() and not got.capped.any()
    p95 = np.percentile(uv_error_texels(got.uv, ref.uv, h.shape[::-1]).reshape(4, -1), 95, axis=1)
    assert (p95 <= 0.02).all(), p95


def test_cheaper_than_maxmip_and_top_offset_matters(gpu):
    h = builtin_height("bumps", (256, 256))
    for angle in (45.0, 80.0):
        quad = measure("quadmax", h, angle, rays=1024)
        maxmip = measure("maxmip", h, angle, rays=1024)
        assert quad.fetches_mean < 0.6 * maxmip.fetches_mean, (angle, quad, maxmip)
        assert quad.error_p95 <= 0.01
    # top_offset -8: leaves only (no quad texel is read), one fetch per 2x2-cell block the ray crosses
    leaves = measure("quadmax", h, 80.0, rays=1024, top_offset=-8)
    assert leaves.fetches_mean > 2 * measure("quadmax", h, 80.0, rays=1024).fetches_mean
    head_on = probe("quadmax", h, random_rays(256, 0.0)[0], [0.0, 0.0, 1.0], 0.05)
    assert (head_on.fetches == 1).all()


@pytest.mark.parametrize("name", ("wall", "step", "spike", "checker"))
def test_axis_aligned_rays_find_the_hit(gpu, name):
    """Rays along +-u / +-v on texel-centre lines and cell borders: a leaf cell the ray only touches by rounding
    must not send the walk back (it once did: 7-texel early hits on the checker at 85 degrees)."""
    from tests.relief.test_contracts import axis_aligned_rays

    h = builtin_height(name, (64, 64))
    for angle in (45.0, 80.0, 85.0):
        for azimuth in (0.0, 90.0, 180.0, 270.0):
            uv, view = axis_aligned_rays(64, angle, azimuth)
            got = probe("quadmax", h, uv, view, 0.05)
            ref = exact_hit(1.0 - h, uv, view, 0.05)
            ok = ref.valid & ~got.capped
            err = uv_error_texels(got.uv[ok], ref.uv[ok], h.shape)
            # the leaves' 14-bit depths may stop a ray up to 6e-5 early: at 85 degrees about 0.04 texel
            assert err.max() <= 0.1, (angle, azimuth, float(err.max()))
