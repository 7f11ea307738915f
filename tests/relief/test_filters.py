"""Texture filters: the registry and its generated interface, the WGSL filters against their float64 twins
(wgpuviewer.lab.studies.filtering.cpu) on the same footprints, visibility on a step, degenerate footprints."""

from __future__ import annotations

import re

import numpy as np
import pytest

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.wgsl import read_wgsl
from wgpuviewer.lab.studies.filtering import cpu
from wgpuviewer.relief import filters
from wgpuviewer.relief.filter_probe import filter_probe, texture_levels
from wgpuviewer.relief.filters import FILTERS, FLAGS
from wgpuviewer.relief.reference import exact_hit, view_dir_from_angles
from wgpuviewer.textures import builtin_albedo, builtin_height

CONTRACT = ("nearest", "bilinear", "trilinear", "aniso", "ewa", "ewa_approx", "ewa_vis", "ewa_vis_rows")
#: Every filter with a float64 twin, by the tolerance its registry entry declares.
TOLERANCE = {f.name: f.twin_tolerance for f in FILTERS.values() if f.twin_tolerance is not None}


# --- the registry -------------------------------------------------------------------------------------------


def test_every_filter_declares_its_twin_or_why_not():
    """A filter has a tolerance against its float64 twin (cpu_filter returns a value for it, and the GPU twin tests
    below run it) or a stated reason it has none (and cpu_filter has no twin for it): never neither, never both."""
    levels = texture_levels(textures()["noise 64x48"])
    for f in FILTERS.values():
        assert (f.twin_tolerance is None) == bool(f.no_twin), f.name
        twin = cpu.cpu_filter(f.name, levels, np.array([0.3, 0.6]), np.array([0.01, 0.0]), np.array([0.0, 0.02]),
                              hidden=cpu.hidden_test(np.zeros((4, 4), np.float32), (0.0, 0.0, 1.0), 0.05))
        assert (twin is not None) == (f.twin_tolerance is not None), f.name
        assert f.twin_tolerance is None or f.twin_tolerance >= 0.0
    twin_tests = set(GPU_TWIN_FILTERS) | set(VISIBILITY_TWIN_FILTERS)
    assert twin_tests == set(TOLERANCE), "every filter with a twin is run against it on the GPU"


def test_markdown_table_lists_every_filter():
    table = filters.markdown_table().splitlines()
    assert table[0] == "| filter | what | reads per lookup |" and len(table) == 2 + len(FILTERS)
    for f, row in zip(FILTERS.values(), table[2:]):
        assert row.startswith(f"| `{f.name}`") and f.cost in row and f.description in row
    assert "`trilinear` (default)" in filters.markdown_table()


def test_the_contract_filters_are_registered():
    assert set(CONTRACT) <= set(FILTERS)
    assert filters.DEFAULT_FILTER == "trilinear" and filters.DEFAULT_DERIVATIVES == "uv"
    assert {"uv", "displaced", "analytic"} <= set(filters.DERIVATIVE_SOURCES)
    for f in FILTERS.values():
        assert read_wgsl(f.wgsl_file)
        for p in f.params:
            assert p.min <= p.default <= p.max, (f.name, p.name)
    for d in filters.DERIVATIVE_SOURCES.values():
        assert "fn texture_derivatives(" in read_wgsl(d.wgsl_file)


def test_anisotropic_samplers_filter_linearly():
    """WebGPU: max_anisotropy > 1 needs linear min, mag and mipmap filters (wgpu-py's defaults are nearest)."""
    for f in FILTERS.values():
        for value in (2, 16):
            d = filters.sampler_descriptor(f, {**f.defaults(), **({"max_anisotropy": value} if f.name == "aniso" else {})})
            if d["max_anisotropy"] > 1:
                assert (d["mag_filter"], d["min_filter"], d["mipmap_filter"]) == ("linear",) * 3


def test_generated_filter_interface_follows_the_registry():
    for f in FILTERS.values():
        text = filters.filter_interface(f).text
        fields = re.findall(r"^    (\w+): ([fiu]32),$", text, re.M)
        assert fields[: len(f.params)] == [(p.name, p.wgsl_type) for p in f.params]
        assert len(fields) * 4 == filters.filter_uniform_size(f) and filters.filter_uniform_size(f) % 16 == 0
        assert len(filters.pack_filter_params(f, f.defaults())) == filters.filter_uniform_size(f)
        for p in f.params:
            assert f"const {p.name.upper()}_MAX: {p.wgsl_type} = " in text
        for name, bit in FLAGS.items():
            assert f"const FLAG_{name.upper()}: u32 = {bit}u;" in text
        assert f"@group({filters.FILTER_GROUP}) @binding(0) var<uniform> filter_params: FilterParams;" in text
    # counts u32, numbers f32, packed in those types
    ewa = filters.filter_params(FILTERS["ewa"])
    assert ewa.fields[:2] == (("max_texels", "u32"), ("alpha", "f32"))
    record = ewa.unpack(filters.pack_filter_params(FILTERS["ewa"], {"max_texels": 64}))[0]
    assert (record["max_texels"], record["alpha"]) == (64, 4.0)


def test_unknown_names_are_user_errors():
    with pytest.raises(UserError, match="unknown filter"):
        filters.get_filter("box", "--filter")
    with pytest.raises(UserError, match="unknown derivative source"):
        filters.get_derivatives("magic", "--derivatives")
    with pytest.raises(UserError, match="max_texels"):
        filters.resolve_filter_params(FILTERS["ewa"], {"max_texels": 0})


# --- the ellipse against closed forms ---------------------------------------------------------------------


def test_isotropic_footprint_is_a_circle():
    for s in (0.25, 1.0, 7.0):
        a, b, c, f = cpu.ellipse_coefficients([s, 0.0], [0.0, s])
        assert a == c == s * s and b == 0 and f == pytest.approx(s**4)
        major, minor, _ = cpu.footprint_axes([s, 0.0], [0.0, s])
        assert major == pytest.approx(s) and minor == pytest.approx(s)
        # rotated: still a circle of radius s
        t = 0.7
        dx, dy = s * np.array([np.cos(t), np.sin(t)]), s * np.array([-np.sin(t), np.cos(t)])
        a, b, c, f = cpu.ellipse_coefficients(dx, dy)
        assert a == pytest.approx(c) and abs(b) < 1e-12 * s * s and f == pytest.approx(s**4)


def test_axis_aligned_footprint_has_its_axes():
    a, b, c, f = cpu.ellipse_coefficients([5.0, 0.0], [0.0, 2.0])  # 5 texels along u per pixel in x, 2 along v
    assert (a, b, c, f) == (4.0, 0.0, 25.0, 100.0)  # 4 U^2 + 25 V^2 = 100: U^2 / 25 + V^2 / 4 = 1
    major, minor, direction = cpu.footprint_axes([5.0, 0.0], [0.0, 2.0])
    assert (major, minor) == (5.0, 2.0) and np.allclose(direction, [1.0, 0.0])
    major, minor, direction = cpu.footprint_axes([2.0, 0.0], [0.0, 5.0])
    assert (major, minor) == (5.0, 2.0) and np.allclose(np.abs(direction), [0.0, 1.0])


def test_ellipse_axes_are_the_jacobians_singular_values():
    rng = np.random.default_rng(1)
    for _ in range(200):
        j = rng.normal(size=(2, 2)) * np.exp(rng.uniform(-3, 3))
        a, b, c, f = cpu.ellipse_coefficients(j[:, 0], j[:, 1])
        assert f == pytest.approx(a * c - b * b / 4, rel=1e-9, abs=1e-12 * (a + c) ** 2)
        major, minor, direction = cpu.footprint_axes(j[:, 0], j[:, 1])
        sv = np.linalg.svd(j, compute_uv=False)
        assert major == pytest.approx(sv[0], rel=1e-7) and minor == pytest.approx(sv[1], rel=1e-6, abs=1e-9 * sv[0])
        u = np.linalg.svd(j)[0][:, 0]
        assert abs(abs(direction @ u) - 1.0) < 1e-6 or sv[0] - sv[1] < 1e-6 * sv[0]
        # every point of the ellipse is the image of a unit pixel offset: Q(J e) = F
        for angle in (0.3, 2.0):
            p = j @ [np.cos(angle), np.sin(angle)]
            assert a * p[0] ** 2 + b * p[0] * p[1] + c * p[1] ** 2 == pytest.approx(f, rel=1e-9)


# --- GPU filters against their float64 twins ------------------------------------------------------------


def footprints(n: int, size: tuple[int, int], seed: int = 0):
    """Random hits and derivatives from magnification (0.05 texel per pixel) to minification (60), isotropic to
    strongly anisotropic, any orientation, some uv far outside [0, 1) (tiling)."""
    rng = np.random.default_rng(seed)
    uv = rng.uniform(-2.0, 3.0, (n, 2))
    scale = np.exp(rng.uniform(np.log(0.05), np.log(60.0), (n, 1))) / max(size)
    dx = rng.normal(size=(n, 2)) * scale
    dy = rng.normal(size=(n, 2)) * scale * rng.uniform(0.02, 1.0, (n, 1))
    return uv, dx, dy


def textures():
    rng = np.random.default_rng(2)
    checker = (np.indices((48, 64)).sum(0) % 2).astype(np.float32)
    return {
        "noise 64x48": rng.random((48, 64, 3)).astype(np.float32),
        "bricks albedo": builtin_albedo("bricks", (64, 64)),
        "1-texel checker": np.repeat(checker[..., None], 3, axis=2),
        "npot 43x37": rng.random((37, 43, 3)).astype(np.float32),
        "1x1": np.full((1, 1, 3), 0.25, np.float32),
    }


def gpu_and_cpu(name, texture, uv, dx, dy, view=(0.0, 0.0, 1.0), height=None, params=None):
    got = filter_probe(name, texture, uv, dx, dy, view, height=height, filter_params=params)
    levels = texture_levels(texture)
    hidden = cpu.hidden_test((1.0 - height).astype(np.float32), view, 0.05) if height is not None else None
    want = [cpu.cpu_filter(name, levels, uv[i], dx[i], dy[i], params=params, hidden=hidden) for i in range(len(uv))]
    return got, want


GPU_TWIN_FILTERS = [n for n in TOLERANCE if not FILTERS[n].visibility]
VISIBILITY_TWIN_FILTERS = [n for n in TOLERANCE if FILTERS[n].visibility]


@pytest.mark.parametrize("name", GPU_TWIN_FILTERS)
def test_gpu_filter_equals_its_float64_twin(gpu, name):
    for label, texture in textures().items():
        uv, dx, dy = footprints(200, texture.shape[1::-1], seed=len(label))
        got, want = gpu_and_cpu(name, texture, uv, dx, dy)
        error = np.abs(got.value - np.array([w.value for w in want])).max(axis=1)
        assert error.max() <= TOLERANCE[name], (label, float(error.max()), int(error.argmax()))
        if FILTERS[name].texel_loop:  # the same texels, visited in the same order
            assert (got.texels == [w.texels for w in want]).all(), label
            assert (got.flags == [w.flags for w in want]).all(), label


@pytest.mark.parametrize("name", VISIBILITY_TWIN_FILTERS)
@pytest.mark.parametrize("relief", ["bricks", "step"])
def test_visibility_filters_equal_their_float64_twins(gpu, name, relief):
    """The GPU traces with maxmip (exact to float32); the twin with the float64 exact hit. Both drop the same
    texels and give the same value, except where a texel's margin is within rounding of the tolerance."""
    texture = textures()["noise 64x48"]
    height = builtin_height(relief, (64, 48))
    depth = (1.0 - height).astype(np.float32)
    for angle, azimuth in ((60.0, 20.0), (85.0, 185.0)):
        view = view_dir_from_angles(angle, azimuth)
        uv, dx, dy = footprints(60, (64, 48), seed=int(angle))
        got, want = gpu_and_cpu(name, texture, uv, dx, dy, view, height)
        ambiguous = np.array([near_tolerance(depth, w, view) for w in want])
        value = np.array([w.value for w in want])
        ok = ~ambiguous
        assert ok.mean() > 0.7
        assert np.abs(got.value - value).max(axis=1)[ok].max() <= TOLERANCE[name], (relief, angle)
        assert (got.hidden[ok] == np.array([w.hidden for w in want])[ok]).all(), (relief, angle)
        assert got.hidden.sum() > 0


def near_tolerance(depth, filtered: cpu.Filtered, view) -> bool:
    """Whether one of the texel centres the twin tested has a float64 margin within a factor 3 of VIS_TOLERANCE:
    float32 traces may decide those either way (near-tangent contacts are ill-conditioned: a maxmip hit 1e-3
    short of the float64 one was seen)."""
    from wgpuviewer.relief.filters import VIS_TOLERANCE

    points = []
    for level, weights in filtered.weights.items():
        h, w = depth.shape
        size = np.array([max(w >> level, 1), max(h >> level, 1)])
        points += [(np.array(t) + 0.5) / size for t in weights]
    if not points:
        return False
    margin = cpu.texel_visibility(depth, np.array(points), view, 0.05).margin
    return bool(((margin > VIS_TOLERANCE / 3) & (margin < 3 * VIS_TOLERANCE)).any())


# --- visibility on flat relief and at a step ------------------------------------------------------------


@pytest.mark.parametrize("relief", ["flat0", "flat1"])
def test_on_flat_relief_ewa_vis_is_ewa(gpu, relief):
    """Nothing is hidden on a flat relief: with the same texel cap the visibility filters take exactly EWA's texels
    with EWA's weights, at any view. (They are other shader modules, so the compiler may round the same sums
    differently: values agree to float32 rounding.)"""
    texture = textures()["bricks albedo"]
    height = builtin_height(relief, (64, 64))
    uv, dx, dy = footprints(300, (64, 64), seed=5)
    for angle in (0.0, 60.0, 85.0, 89.0):
        view = view_dir_from_angles(angle, 33.0)
        cap = {"max_texels": 256}
        plain = filter_probe("ewa", texture, uv, dx, dy, view, height=height, filter_params=cap)
        for name in ("ewa_vis", "ewa_vis_rows"):
            vis = filter_probe(name, texture, uv, dx, dy, view, height=height, filter_params=cap)
            assert (vis.flags == plain.flags).all() and (vis.texels == plain.texels).all(), (name, angle)
            assert (vis.hidden == 0).all()
            assert np.abs(vis.value - plain.value).max() < 1e-6, (name, angle)
            assert (vis.depth_fetches > 0).all()  # the test ran: each texel was traced


def step_case(angle: float = 80.0):
    """A 64x64 step (height 1 for u >= 0.5) seen from +u at ``angle``: the low side just left of the step is
    hidden behind it. Footprints at real hits near the edge (the float64 exact hits of rays entering on either
    side), at level 0 (minor semi-axis 0.8 texel), elongated along the view."""
    height = builtin_height("step", (64, 64))
    view = view_dir_from_angles(angle, 0.0)
    rng = np.random.default_rng(7)
    entries = np.stack([rng.uniform(0.4, 0.9, 2000), rng.uniform(0.0, 1.0, 2000)], axis=1)
    hit = exact_hit(1.0 - height, entries, view, 0.05)
    uv = hit.uv[hit.valid & (hit.uv[:, 0] > 0.36) & (hit.uv[:, 0] < 0.52)][:200]
    n = len(uv)
    dx = np.stack([rng.uniform(3.0, 12.0, n), rng.normal(0.0, 0.5, n)], axis=1) / 64  # along the view
    dy = np.stack([np.zeros(n), np.full(n, 0.8)], axis=1) / 64
    return height, view, uv, dx, dy


def test_at_a_grazing_step_hidden_texels_get_no_weight(gpu):
    """An indicator texture, 1 on the texels the float64 reference says are hidden (by a clear margin) and 0
    elsewhere: ewa_vis must average exactly 0 over every footprint, while plain EWA sees the hidden ones."""
    height, view, uv, dx, dy = step_case()
    depth = (1.0 - height).astype(np.float32)
    centres = (np.stack(np.meshgrid(np.arange(64), np.arange(64)), -1).reshape(-1, 2) + 0.5) / 64
    vis = cpu.texel_visibility(depth, centres, view, 0.05)
    clearly = (vis.margin > 0.05).reshape(64, 64)
    assert 0.05 < clearly.mean() < 0.5  # a real shadow of the step, not everything
    indicator = np.repeat(clearly[..., None].astype(np.float32), 3, axis=2)
    plain = filter_probe("ewa", indicator, uv, dx, dy, view, height=height)
    assert (plain.value[:, 0] > 0.01).mean() > 0.5  # most footprints reach behind the step
    for name in ("ewa_vis", "ewa_vis_rows"):
        got = filter_probe(name, indicator, uv, dx, dy, view, height=height)
        assert (got.value[:, 0] == 0.0).all(), name
        assert (got.hidden > 0).mean() > 0.5


def test_row_ends_method_keeps_the_gain_at_a_step(gpu):
    """At a straight step the hidden texels of a row are one run, the case Romanyuk & Dudnyk 2017's cheap method assumes: it
    gives the full method's value while tracing fewer texels."""
    height, view, uv, dx, dy = step_case()
    texture = textures()["noise 64x48"]
    full = filter_probe("ewa_vis", texture, uv, dx, dy, view, height=height)
    rows = filter_probe("ewa_vis_rows", texture, uv, dx, dy, view, height=height)
    assert np.abs(full.value - rows.value).max() < 1e-5
    assert (rows.depth_fetches <= full.depth_fetches).all() and rows.depth_fetches.sum() < full.depth_fetches.sum()


# --- degenerate footprints -------------------------------------------------------------------------------


#: Degenerate footprints: uv, dx, dy, the flag a filter that uses derivatives must set (0: none).
DEGENERATE = {
    "zero": ([0.3, 0.6], [0.0, 0.0], [0.0, 0.0], 0),
    "nan dx": ([0.3, 0.6], [np.nan, 0.1], [0.0, 0.01], FLAGS["nonfinite"]),
    "inf dy": ([0.3, 0.6], [0.01, 0.0], [0.0, -np.inf], FLAGS["nonfinite"]),
    "nan uv": ([np.nan, 0.6], [0.01, 0.0], [0.0, 0.01], FLAGS["nonfinite"]),
    "huge": ([0.3, 0.6], [1e30, 3e29], [1e-3, 2e30], FLAGS["huge"]),
    "huge thin": ([0.3, 0.6], [1e20, 0.0], [0.0, 1e-20], FLAGS["huge"]),
    "far tiling": ([1e5 + 0.3, -1e5], [0.01, 0.0], [0.0, 0.01], 0),
}


@pytest.mark.parametrize("name", list(FILTERS))
def test_zero_nan_and_huge_derivatives_are_finite_and_flagged(gpu, name):
    texture = textures()["bricks albedo"]
    height = builtin_height("bricks", (64, 64))
    cases = DEGENERATE
    uv, dx, dy, want = (np.array([c[k] for c in cases.values()]) for k in range(4))
    f = FILTERS[name]
    for view in ((0.0, 0.0, 1.0), view_dir_from_angles(89.9, 10.0), (1.0, 0.0, 0.0)):
        got = filter_probe(name, texture, uv, dx, dy, view, height=height if f.visibility else None)
        assert np.isfinite(got.value).all(), (name, view)
        assert ((got.value >= -1e-6) & (got.value <= 1.0 + 1e-6)).all()
        loops = f.texel_loop or name == "ewa_approx"
        for i, label in enumerate(cases):
            flag = int(want[i])
            if flag == FLAGS["huge"] and not (loops or name == "aniso"):
                continue  # hardware samplers take huge derivatives as they are (the coarsest level)
            if flag and (f.uses_derivatives or flag != FLAGS["huge"]) and (label != "nan dx" and label != "inf dy"
                                                                           or f.uses_derivatives):
                assert got.flags[i] & flag, (name, label, got.flags[i])
        if f.texel_loop:
            assert (got.texels <= f.defaults()["max_texels"]).all()


def test_texel_cap_raises_the_level_and_flags(gpu):
    texture = textures()["noise 64x48"]
    uv = np.array([[0.4, 0.4]])
    dx, dy = np.array([[30.0, 0.0]]) / 64, np.array([[0.0, 1.0]]) / 64  # 30 x 1 texels: ~190 texels at level 0
    roomy = filter_probe("ewa", texture, uv, dx, dy, filter_params={"max_texels": 4096})
    tight = filter_probe("ewa", texture, uv, dx, dy, filter_params={"max_texels": 16})
    assert not roomy.flags[0] & FLAGS["capped"] and roomy.texels[0] > 100
    assert tight.flags[0] & FLAGS["capped"] and tight.texels[0] <= 16
    assert np.isfinite(tight.value).all()
