"""Texture loading: builtins (exact hard cases, tiling, determinism) and files (bit depths, channels, errors)."""

import cv2
import numpy as np
import pytest

from wgpuviewer import textures
from wgpuviewer.core.errors import UserError
from wgpuviewer.textures import (
    BUILTINS,
    TextureRef,
    builtin_albedo,
    builtin_height,
    load_albedo,
    load_depth,
    load_height,
    load_normal_map,
    read_image,
)

RELIEF = ("bricks", "bumps", "ridges")


@pytest.fixture(autouse=True)
def _fresh_cache():
    textures.clear_cache()
    yield
    textures.clear_cache()


def file_ref(path, channel="auto") -> TextureRef:
    return TextureRef("file", path=path, channel=channel)


def write_png(path, data):
    assert cv2.imwrite(str(path), data)
    return path


# --- builtins ----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(BUILTINS))
def test_builtin_shape_dtype_range(name):
    h = builtin_height(name, (48, 40))
    a = builtin_albedo(name, (48, 40))
    assert h.shape == (40, 48) and h.dtype == np.float32
    assert a.shape == (40, 48, 3) and a.dtype == np.float32
    assert h.min() >= 0 and h.max() <= 1 and a.min() >= 0 and a.max() <= 1
    assert not h.flags.writeable and not a.flags.writeable


@pytest.mark.parametrize("name", RELIEF)
def test_builtin_deterministic(name):
    first = builtin_height(name, (64, 32)).copy()
    textures.clear_cache()
    np.testing.assert_array_equal(first, builtin_height(name, (64, 32)))


@pytest.mark.parametrize("name", RELIEF)
def test_builtin_tileable(name):
    h = builtin_height(name, (128, 96)).astype(np.float64)
    for axis in (0, 1):
        inner = np.abs(np.diff(h, axis=axis)).mean(axis=axis)  # typical step between neighbours
        seam = np.abs(h.take(0, axis=axis) - h.take(-1, axis=axis))  # step across the wrap
        assert seam.mean() <= 2 * inner.mean() + 1e-3, (name, axis)


@pytest.mark.parametrize("name", RELIEF)
def test_builtin_relief_has_relief(name):
    h = builtin_height(name)
    assert h.shape == (256, 256) and h.max() - h.min() > 0.5


def test_bricks_albedo_is_reddish_with_grey_mortar():
    h, a = builtin_height("bricks", (128, 128)), builtin_albedo("bricks", (128, 128))
    brick, mortar = a[h > 0.7].mean(axis=0), a[h < 0.2].mean(axis=0)
    assert brick[0] > 2 * brick[2]
    assert np.ptp(mortar) < 0.1


def test_hard_cases_exact():
    w, h = 32, 16
    assert np.all(builtin_height("flat0", (w, h)) == 0)
    assert np.all(builtin_height("flat1", (w, h)) == 1)
    spike = builtin_height("spike", (w, h))
    assert spike[h // 2, w // 2] == 1 and spike.sum() == 1
    step = builtin_height("step", (w, h))
    assert np.all(step[:, : w // 2] == 0) and np.all(step[:, w // 2 :] == 1)
    wall = builtin_height("wall", (w, h))
    assert np.all(wall[:, w // 2] == 1) and wall.sum() == h
    checker = builtin_height("checker", (w, h))
    ys, xs = np.indices((h, w))
    np.testing.assert_array_equal(checker, (xs // 8 + ys // 8) % 2)
    assert set(np.unique(checker)) == {0.0, 1.0}


@pytest.mark.parametrize("size", [(1, 1), (343, 401)])
@pytest.mark.parametrize("name", ["bricks", "spike", "checker"])
def test_builtin_odd_sizes(name, size):
    assert builtin_height(name, size).shape == size[::-1]


def test_unknown_builtin_lists_known():
    with pytest.raises(UserError, match="bumps"):
        builtin_height("nope")


def test_builtin_refs_and_depth():
    ref = TextureRef("builtin", name="step", size=(8, 4))
    np.testing.assert_array_equal(load_height(ref), builtin_height("step", (8, 4)))
    np.testing.assert_array_equal(load_depth(ref), 1 - builtin_height("step", (8, 4)))
    np.testing.assert_array_equal(load_height(ref, is_depth=True), 1 - builtin_height("step", (8, 4)))
    assert load_albedo(ref).shape == (4, 8, 3)


def test_color_albedo():
    a = load_albedo(TextureRef("color", color=(0.25, 0.5, 1.0)))
    assert a.shape == (1, 1, 3) and a.dtype == np.float32
    np.testing.assert_allclose(a[0, 0], [0.25, 0.5, 1.0])


def test_cached_and_read_only():
    ref = TextureRef("builtin", name="bumps", size=(16, 16))
    assert load_height(ref) is load_height(ref)
    with pytest.raises(ValueError):
        load_height(ref)[0, 0] = 0.5


# --- files -------------------------------------------------------------------------------------


def test_8bit_grey(tmp_path):
    data = np.array([[0, 51, 255]], np.uint8)
    h = load_height(file_ref(write_png(tmp_path / "g.png", data)))
    assert h.dtype == np.float32
    np.testing.assert_allclose(h, [[0, 0.2, 1]], atol=1e-6)


def test_16bit_grey(tmp_path):
    data = np.array([[0, 65535], [32768, 1]], np.uint16)
    h = load_height(file_ref(write_png(tmp_path / "g16.png", data)))
    np.testing.assert_allclose(h, data / 65535, atol=1e-6)


def test_float_npy(tmp_path):
    data = np.linspace(0, 1, 12, dtype=np.float64).reshape(3, 4)
    np.save(tmp_path / "h.npy", data)
    np.testing.assert_allclose(load_height(file_ref(tmp_path / "h.npy")), data, atol=1e-7)


def test_depth_file_converted(tmp_path):
    np.save(tmp_path / "d.npy", np.array([[0.0, 0.25]], np.float32))
    ref = file_ref(tmp_path / "d.npy")
    np.testing.assert_allclose(load_height(ref, is_depth=True), [[1.0, 0.75]])
    np.testing.assert_allclose(load_depth(ref, is_depth=True), [[0.0, 0.25]])


@pytest.fixture
def rgba_png(tmp_path):
    """A 2x3 RGBA image with distinct constant channels: r=10, g=20, b=30, a=40 (stored as BGRA)."""
    bgra = np.empty((2, 3, 4), np.uint8)
    bgra[...] = [30, 20, 10, 40]
    return write_png(tmp_path / "rgba.png", bgra)


@pytest.mark.parametrize("channel,value", [("r", 10), ("g", 20), ("b", 30), ("a", 40)])
def test_channel_selection_maps_bgr(rgba_png, channel, value):
    np.testing.assert_allclose(read_image(rgba_png, channel), value / 255)
    np.testing.assert_allclose(load_height(file_ref(rgba_png, channel)), value / 255)


def test_auto_channel_order_and_luminance(rgba_png):
    np.testing.assert_allclose(read_image(rgba_png)[0, 0], np.array([10, 20, 30, 40]) / 255)
    lum = (0.2126 * 10 + 0.7152 * 20 + 0.0722 * 30) / 255
    np.testing.assert_allclose(load_height(file_ref(rgba_png)), lum, rtol=1e-5)


def test_albedo_file_srgb_decoded(tmp_path):
    bgr = np.zeros((1, 2, 3), np.uint8)
    bgr[0, 0] = [0, 0, 255]  # red
    bgr[0, 1] = [128, 128, 128]
    a = load_albedo(file_ref(write_png(tmp_path / "a.png", bgr)))
    np.testing.assert_allclose(a[0, 0], [1, 0, 0])
    np.testing.assert_allclose(a[0, 1], ((128 / 255 + 0.055) / 1.055) ** 2.4, rtol=1e-5)  # ~0.216


def test_missing_channel(tmp_path):
    rgb = write_png(tmp_path / "rgb.png", np.zeros((2, 2, 3), np.uint8))
    with pytest.raises(UserError, match=r"rgb\.png: channel 'a'.*3-channel"):
        read_image(rgb, "a")
    grey = write_png(tmp_path / "grey.png", np.full((2, 2), 51, np.uint8))
    with pytest.raises(UserError, match=r"grey\.png: channel 'a'.*greyscale"):
        load_height(file_ref(grey, "a"))
    np.testing.assert_allclose(load_height(file_ref(grey, "r")), 0.2)  # grey: its value in every colour channel


@pytest.mark.parametrize("bad,count", [(np.nan, 1), (np.inf, 2)])
def test_non_finite_rejected(tmp_path, bad, count):
    data = np.zeros((3, 3), np.float32)
    data.flat[:count] = bad
    np.save(tmp_path / "bad.npy", data)
    with pytest.raises(UserError) as e:
        load_height(file_ref(tmp_path / "bad.npy"))
    msg = str(e.value)
    assert "bad.npy" in msg and f"{count} non-finite" in msg and "clean the data" in msg and "\n" not in msg


def test_float_out_of_range(tmp_path):
    np.save(tmp_path / "big.npy", np.array([[0.0, 2.5]], np.float32))
    with pytest.raises(UserError, match=r"big\.npy: height values range from 0 to 2\.5; expected \[0, 1\]"):
        load_height(file_ref(tmp_path / "big.npy"))


def test_unsupported_dtype(tmp_path):
    np.save(tmp_path / "i.npy", np.zeros((2, 2), np.int32))
    with pytest.raises(UserError, match=r"i\.npy: unsupported dtype int32"):
        read_image(tmp_path / "i.npy")


def test_empty_image(tmp_path):
    np.save(tmp_path / "e.npy", np.zeros((0, 4), np.float32))
    with pytest.raises(UserError, match=r"e\.npy: empty image"):
        read_image(tmp_path / "e.npy")


def test_corrupt_and_missing_files(tmp_path):
    (tmp_path / "junk.png").write_bytes(b"not a png at all")
    with pytest.raises(UserError, match=r"junk\.png: cannot decode image"):
        load_height(file_ref(tmp_path / "junk.png"))
    (tmp_path / "junk.npy").write_bytes(b"garbage")
    with pytest.raises(UserError, match=r"junk\.npy: cannot read \.npy"):
        read_image(tmp_path / "junk.npy")
    with pytest.raises(UserError, match=r"gone\.png: file not found"):
        read_image(tmp_path / "gone.png")


@pytest.mark.parametrize("shape", [(1, 1), (401, 343)])
def test_small_and_npot_files(tmp_path, shape):
    data = np.random.default_rng(0).integers(0, 256, shape, dtype=np.uint8)
    h = load_height(file_ref(write_png(tmp_path / "x.png", data)))
    assert h.shape == shape
    np.testing.assert_allclose(h, data / 255, atol=1e-6)


# --- normal maps -------------------------------------------------------------------------------


def normal_png(tmp_path, rgb):
    bgr = np.empty((2, 2, 3), np.uint8)
    bgr[...] = rgb[::-1]
    return write_png(tmp_path / "n.png", bgr)


def test_normal_map_opengl_and_directx(tmp_path):
    ref = file_ref(normal_png(tmp_path, [128, 200, 230]))  # tilted towards +green
    gl = load_normal_map(ref, "opengl")
    dx = load_normal_map(ref, "directx")
    assert gl.shape == (2, 2, 3) and gl.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(gl, axis=2), 1, atol=1e-6)
    assert gl[0, 0, 1] > 0.4
    np.testing.assert_allclose(dx[..., 1], -gl[..., 1])
    np.testing.assert_allclose(dx[..., [0, 2]], gl[..., [0, 2]])


def test_flat_normal_map(tmp_path):
    n = load_normal_map(file_ref(normal_png(tmp_path, [128, 128, 255])), "opengl")
    np.testing.assert_allclose(n[0, 0], [0, 0, 1], atol=0.01)


def test_normal_map_needs_colour(tmp_path):
    grey = write_png(tmp_path / "g.png", np.zeros((2, 2), np.uint8))
    with pytest.raises(UserError, match="greyscale"):
        load_normal_map(file_ref(grey), "opengl")
