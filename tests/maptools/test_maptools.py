"""maptools kernels: GPU vs CPU on realistic and adversarial maps, and the algorithms' own properties."""

from __future__ import annotations

import re

import cv2
import numpy as np
import pytest

import maptools
from maptools.registry import KINDS
from tests.conftest import adapter_summary
from tests.maptools.helpers import adversarial_maps, smooth_tileable
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.images import read_height

MAPS = adversarial_maps()
# -- GPU vs CPU ------------------------------------------------------------------------------------

#: Each kind's declared cross-checks, on every test map within the case's size bound.
CASES = [(kind, case, name) for kind, k in KINDS.items() for case in k.cases for name in sorted(MAPS)
         if case.max_texels is None or MAPS[name].size <= case.max_texels]


def test_every_kind_declares_valid_cross_checks():
    for kind, k in KINDS.items():
        assert k.cases, f"{kind}: no cross-check cases (registry.Kind.cases)"
        for case in k.cases:
            k.resolve(case.options)  # names and values the kind accepts
    assert {kind for kind, _, _ in CASES} == set(KINDS)  # every kind is cross-checked on some test map


@pytest.mark.requires_gpu
@pytest.mark.parametrize("kind,case,name", CASES,
                         ids=[f"{k}-{'-'.join(map(str, c.options.values())) or 'default'}-{n}" for k, c, n in CASES])
def test_gpu_matches_cpu(kind, case, name):
    height = MAPS[name]
    k = KINDS[kind]
    resolved = k.resolve(case.options)
    a = maptools.generate(kind, height, backend="cpu", **case.options)
    b = maptools.generate(kind, height, backend="gpu", **case.options)
    c = k.compare(a, b, resolved)
    assert c.ok, (kind, name, c)
    if kind == "normal":
        assert b.shape == height.shape + (3,) and b.dtype == np.float32
    elif kind == "complexity":
        assert b.dtype == np.uint8 and b.shape == height.shape
        assert np.array_equal(a, b), "complexity is bit-exact on lavapipe; a flip here needs a look"


@pytest.mark.requires_gpu
@pytest.mark.parametrize("opts", [{"ksize": 5}, {"gamma": 0.9, "dilate_kernel": 5}, {"levels": 2},
                                  {"levels": 256, "iterations": 0}, {"ksize": 5, "border": "clamp"}])
def test_complexity_variants_gpu_matches_cpu(opts):
    for name in ("smooth_343x401", "spike", "noise_odd", "one_texel"):
        a = maptools.generate("complexity", MAPS[name], backend="cpu", **opts)
        b = maptools.generate("complexity", MAPS[name], backend="gpu", **opts)
        c = KINDS["complexity"].compare(a, b, KINDS["complexity"].resolve(opts))
        assert c.ok, (name, opts, c)


@pytest.mark.requires_gpu
def test_gpu_refuses_oversized_maps():
    from maptools import gpu

    g = gpu.runner()
    dim = g.device.limits["max-texture-dimension-2d"]
    with pytest.raises(UserError, match="max texture dimension"):
        g.check_size(4, dim + 1)


# -- normal ------------------------------------------------------------------------------------------

def test_normal_conventions():
    ramp_u = np.tile(np.linspace(0, 1, 16, dtype=np.float32), (16, 1))  # height increases with u (column)
    n = maptools.generate("normal", ramp_u, backend="cpu", border="clamp")
    inner = n[4:-4, 4:-4]
    assert (inner[..., 0] < 0).all() and np.allclose(inner[..., 1], 0, atol=1e-7)
    ramp_v = ramp_u.T.copy()  # height increases with the row index (= v)
    gl = maptools.generate("normal", ramp_v, backend="cpu", border="clamp", y="opengl")[4:-4, 4:-4]
    dx = maptools.generate("normal", ramp_v, backend="cpu", border="clamp", y="directx")[4:-4, 4:-4]
    assert (gl[..., 1] > 0).all() and (dx[..., 1] < 0).all()
    assert np.allclose(gl[..., 1], -dx[..., 1]) and np.allclose(gl[..., 0], 0, atol=1e-7)
    # slope per texel = 1/15; strength 15 -> slope 1 -> 45 degrees
    s = maptools.generate("normal", ramp_u, backend="cpu", border="clamp", strength=15.0)[8, 8]
    assert np.allclose(s, [-np.sqrt(0.5), 0, np.sqrt(0.5)], atol=1e-5)


@pytest.mark.parametrize("name", sorted(MAPS))
def test_normal_unit_and_flat(name):
    n = maptools.generate("normal", MAPS[name], backend="cpu")
    assert np.isfinite(n).all()
    assert np.allclose(np.linalg.norm(n, axis=-1), 1, atol=1e-6)
    if name.startswith("flat") or name == "one_texel":
        assert np.array_equal(n, np.broadcast_to(np.float32([0, 0, 1]), n.shape))


def test_normal_repeat_border_tiles():
    h = smooth_tileable(32, 48, 7)
    rolled = maptools.generate("normal", np.roll(h, (5, 9), axis=(0, 1)), backend="cpu")
    assert np.allclose(np.roll(maptools.generate("normal", h, backend="cpu"), (5, 9), axis=(0, 1)), rolled)


# -- complexity ------------------------------------------------------------------------------------

def thesis_listing(height_map_bgr: np.ndarray) -> np.ndarray:
    """complexity_calculator.py as it runs (dilation_iterations=5, num_levels=24, gamma=0.8), then uint8."""
    gray = height_map_bgr[:, :, 0].astype(np.float32) / 255.0
    grad_x = cv2.Sobel(gray, cv2.CV_32F, 1, 0, ksize=3)
    grad_y = cv2.Sobel(gray, cv2.CV_32F, 0, 1, ksize=3)
    gradient_magnitude = np.sqrt(grad_x ** 2 + grad_y ** 2)
    max_gradient_value = np.max(gradient_magnitude)
    complexity_value = np.clip(gradient_magnitude / max_gradient_value, 0, 1)
    kernel = np.ones((3, 3), np.uint8)
    complexity_value = cv2.dilate(complexity_value, kernel, iterations=5)
    complexity_value = np.power(complexity_value, 0.8)
    step_size = 1.0 / (24 - 1)
    complexity_value = np.round(complexity_value / step_size) * step_size
    return (complexity_value * 255).astype(np.uint8)


def test_complexity_defaults_match_thesis_listing(tmp_path):
    rng = np.random.default_rng(11)
    bgr = np.stack([np.round(smooth_tileable(96, 120, 9) * 255),
                    rng.integers(0, 256, (96, 120)), rng.integers(0, 256, (96, 120))], -1).astype(np.uint8)
    bgr[40:50, 30:90, 0] = 255  # a plateau, so that several levels occur
    path = tmp_path / "h.png"
    cv2.imwrite(str(path), bgr)
    expected = thesis_listing(cv2.imread(str(path), cv2.IMREAD_COLOR))
    assert len(np.unique(expected)) > 8
    height = read_height(path, channel="b")  # the listing reads channel 0 of BGR = blue
    assert np.array_equal(maptools.generate("complexity", height, backend="cpu"), expected)
    if adapter_summary():
        assert np.array_equal(maptools.generate("complexity", height, backend="gpu"), expected)


@pytest.mark.parametrize("value", [0.0, 1.0, 0.37])
def test_complexity_flat_is_zero(value):
    c = maptools.generate("complexity", np.full((9, 13), value, np.float32), backend="cpu")
    assert c.dtype == np.uint8 and not c.any()


@pytest.mark.parametrize("levels", [1, 0, -3])
def test_complexity_levels_below_two_is_an_error(levels):
    with pytest.raises(UserError, match="levels must be >= 2"):
        maptools.generate("complexity", MAPS["spike"], backend="cpu", levels=levels)


def test_complexity_levels_are_quantised():
    c = maptools.generate("complexity", MAPS["smooth_343x401"], backend="cpu", levels=5)
    allowed = {int(np.float32(np.float32(k) * np.float32(0.25)) * np.float32(255)) for k in range(5)}
    assert set(np.unique(c).tolist()) <= allowed


@pytest.mark.parametrize("bad", [{"ksize": 7}, {"dilate_kernel": 4}, {"gamma": float("nan")}, {"border": "mirror"},
                                 {"nonsense": 1}])
def test_complexity_bad_options(bad):
    with pytest.raises(UserError):
        maptools.generate("complexity", MAPS["spike"], backend="cpu", **bad)


# -- maxmip ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("shape", [(1, 1), (1, 7), (5, 3), (16, 16), (343, 401), (2, 9)])
def test_maxmip_is_conservative(shape):
    h = np.random.default_rng(sum(shape)).random(shape).astype(np.float32)
    levels = maptools.generate("maxmip", h, backend="cpu")
    assert np.array_equal(levels[0], h) and levels[-1].shape == (1, 1) and levels[-1][0, 0] == h.max()
    for child, parent in zip(levels, levels[1:]):
        ch, cw = child.shape
        ph, pw = parent.shape
        assert (ph, pw) == ((ch + 1) // 2, (cw + 1) // 2)
        for i in range(ph):
            # index-space children 2i..2i+1 (clamped) and every child the parent's UV span overlaps
            r_idx = range(2 * i, min(2 * i + 2, ch))
            r_uv = range(int(np.floor(i * ch / ph)), int(np.ceil((i + 1) * ch / ph)))
            for j in range(pw):
                c_idx = range(2 * j, min(2 * j + 2, cw))
                c_uv = range(int(np.floor(j * cw / pw)), int(np.ceil((j + 1) * cw / pw)))
                for rows, cols in ((r_idx, c_idx), (r_uv, c_uv)):
                    assert parent[i, j] >= child[rows.start:rows.stop, cols.start:cols.stop].max()
        # and never more than the max of the (at most 3x3) children it covers
        assert parent.max() <= child.max()


def test_maxmip_even_sizes_are_plain_2x2_max():
    h = smooth_tileable(8, 16, 3)
    levels = maptools.generate("maxmip", h, backend="cpu")
    assert np.array_equal(levels[1], h.reshape(4, 2, 8, 2).max(axis=(1, 3)))
    assert [lv.shape for lv in levels] == [(8, 16), (4, 8), (2, 4), (1, 2), (1, 1)]


# -- input validation --------------------------------------------------------------------------------

@pytest.mark.parametrize("kind", list(KINDS))
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_input_is_an_error(kind, bad):
    h = MAPS["noise_odd"].copy()
    h[3, 4] = bad
    with pytest.raises(UserError, match="NaN/inf"):
        maptools.generate(kind, h, backend="cpu")


@pytest.mark.parametrize("bad", [np.zeros((2, 2, 2), np.float32), np.zeros((0, 4), np.float32),
                                 np.full((3, 3), 1.5, np.float32), np.full((3, 3), -0.1, np.float32)])
def test_bad_arrays_are_user_errors(bad):
    with pytest.raises(UserError):
        maptools.generate("normal", bad, backend="cpu")


def test_unknown_kind_and_backend():
    with pytest.raises(UserError, match="unknown map kind"):
        maptools.generate("bogus", MAPS["spike"], backend="cpu")
    with pytest.raises(UserError, match="--backend"):
        maptools.generate("normal", MAPS["spike"], backend="vulkan")


def test_auto_backend_falls_back_to_cpu_with_notice(monkeypatch, capsys):
    from maptools import gpu
    from wgpuviewer.core.errors import NoAdapterError

    def no_adapter(*a, **k):
        raise NoAdapterError("no GPU adapter found")

    monkeypatch.setattr(gpu, "runner", no_adapter)
    monkeypatch.setattr(maptools, "_notice_printed", False)
    n = maptools.generate("normal", MAPS["spike"], backend="auto")
    assert np.array_equal(n, maptools.generate("normal", MAPS["spike"], backend="cpu"))
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "CPU" in err
    with pytest.raises(NoAdapterError):
        maptools.generate("normal", MAPS["spike"], backend="gpu")


def test_the_map_kind_table_has_a_row_per_kind():
    """``registry.markdown_table`` (the README's map-kind table): one row per kind, five cells each (a ``|`` in a
    tolerance is escaped), naming the kernels the kind's cache key hashes."""
    from maptools.registry import markdown_table

    rows = markdown_table().splitlines()[2:]
    assert [r.split(" | ")[0] for r in rows] == [f"| `{k}`" for k in KINDS]
    for row, kind in zip(rows, KINDS.values()):
        assert len(re.split(r"(?<!\\)\|", row)) == 7, row  # 5 cells between 6 bars
        assert all(f"`{f}`" in row for f in kind.kernels)
