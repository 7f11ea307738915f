"""The one reader's header check (wgpuviewer.core.images.read_header): sizes, emptiness, truncation and folders
are refused from the first bytes, before any data is loaded, for every format it reads."""

from __future__ import annotations

import struct
import tracemalloc
import zlib

import cv2
import numpy as np
import pytest

from maptools import cli as maptools_cli
from wgpuviewer.core.errors import FileError
from wgpuviewer.core.images import MAX_SIDE, ImageBytes, read_header, read_height, read_image

HUGE = 60000  # 60000 x 60000 float32 would be 14.4 GB


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def huge_png(path, w=HUGE, h=HUGE):
    ihdr = struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", ihdr) + _chunk(b"IDAT", zlib.compress(b"\0" * 64))
                     + _chunk(b"IEND", b""))
    return path


def huge_jpeg(path, w=HUGE, h=HUGE):
    sof = b"\xff\xc0" + struct.pack(">HBHHB", 11, 8, h, w, 1) + bytes([1, 0x11, 0])
    sos = b"\xff\xda" + struct.pack(">HB", 8, 1) + bytes([1, 0, 0, 63, 0])
    path.write_bytes(b"\xff\xd8" + sof + sos + b"\0" * 16 + b"\xff\xd9")
    return path


EXR_UINT, EXR_HALF, EXR_FLOAT = 0, 1, 2


def huge_exr(path, w=HUGE, h=HUGE, channels=(("Y", EXR_FLOAT, 1),), flags=0, kind=b""):
    """An EXR header and no pixel data: ``channels`` as (name, pixel type, sampling), ``flags`` in the version
    field, ``kind`` the ``type`` attribute (empty: none; a deep type comes with the attributes deep data needs)."""
    def attribute(name: bytes, kind: bytes, value: bytes) -> bytes:
        return name + b"\0" + kind + b"\0" + struct.pack("<i", len(value)) + value

    chlist = b"".join(name.encode() + b"\0" + struct.pack("<iB3xii", pixel_type, 0, sampling, sampling)
                      for name, pixel_type, sampling in channels) + b"\0"
    deep = (attribute(b"chunkCount", b"int", struct.pack("<i", h)) + attribute(b"version", b"int", struct.pack("<i", 1))
            + attribute(b"compression", b"compression", b"\0") if kind.startswith(b"deep") else b"")
    path.write_bytes(b"\x76\x2f\x31\x01" + struct.pack("<i", 2 | flags)
                     + attribute(b"channels", b"chlist", chlist)
                     + (attribute(b"type", b"string", kind) if kind else b"") + deep
                     + attribute(b"dataWindow", b"box2i", struct.pack("<4i", 0, 0, w - 1, h - 1)) + b"\0" * 65)
    return path


def huge_npy(path, w=HUGE, h=HUGE):
    with open(path, "wb") as f:
        np.lib.format.write_array_header_1_0(f, {"descr": "<f4", "fortran_order": False, "shape": (h, w)})
        f.write(b"\0" * 64)  # the data a real file would have is 14.4 GB
    return path


HUGE_FILES = {"png": huge_png, "jpg": huge_jpeg, "exr": huge_exr, "npy": huge_npy}


@pytest.mark.parametrize("ext", list(HUGE_FILES))
def test_a_file_declaring_a_huge_size_is_refused_before_loading(tmp_path, ext):
    path = HUGE_FILES[ext](tmp_path / f"huge.{ext}")
    tracemalloc.start()
    try:
        for read in (read_header, read_image, read_height):
            with pytest.raises(FileError, match=f"{HUGE}x{HUGE} is larger than the limit of {MAX_SIDE} texels"):
                read(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 2 * 2**20, peak  # a few header bytes, not gigabytes


def test_sizes_at_the_limit_pass_the_header_check(tmp_path):
    assert read_header(huge_png(tmp_path / "edge.png", MAX_SIDE, 3)).width == MAX_SIDE
    with pytest.raises(FileError, match="larger than the limit"):
        read_header(huge_npy(tmp_path / "over.npy", 3, MAX_SIDE + 1))


def write(path, data):
    assert cv2.imwrite(str(path), data)
    return path


@pytest.fixture
def good(tmp_path):
    rng = np.random.default_rng(0)
    np.save(tmp_path / "g.npy", rng.random((32, 40)).astype(np.float32))
    return {
        "png": write(tmp_path / "g.png", rng.integers(0, 255, (32, 40), dtype=np.uint8)),
        "png16": write(tmp_path / "g16.png", rng.integers(0, 65535, (32, 40, 3), dtype=np.uint16)),
        "jpg": write(tmp_path / "g.jpg", rng.integers(0, 255, (32, 40, 3), dtype=np.uint8)),
        "npy": tmp_path / "g.npy",
    }


def test_good_files_headers(good):
    for name, path in good.items():
        header = read_header(path)
        assert (header.width, header.height) == (40, 32), name
    assert read_header(good["png16"]).channels == 3 and read_header(good["npy"]).format == "npy"


@pytest.mark.parametrize("name", ["png", "png16", "jpg", "npy"])
def test_empty_truncated_and_folder_inputs(good, tmp_path, name):
    src = good[name]
    data = src.read_bytes()
    cases = {
        "empty": (b"", r"empty file \(0 bytes\)"),
        "cut": (data[: len(data) // 2], "truncated"),
        "head": (data[:12], "truncated" if name == "npy" else "damaged or truncated"),
    }
    for case, (content, message) in cases.items():
        path = tmp_path / f"{case}{src.suffix}"
        path.write_bytes(content)
        for read in (read_header, read_image, read_height):
            with pytest.raises(FileError, match=message) as error:
                read(path)
            assert str(error.value).startswith(f"{path}: ") and "\n" not in str(error.value)
    folder = tmp_path / f"folder{src.suffix}"
    folder.mkdir()
    with pytest.raises(FileError, match="is a directory"):
        read_height(folder)


def test_unsupported_contents_and_shapes(tmp_path):
    (tmp_path / "text.png").write_text("hello, not an image")
    with pytest.raises(FileError, match="cannot decode image"):
        read_header(tmp_path / "text.png")
    np.save(tmp_path / "five.npy", np.zeros((4, 4, 5), np.float32))
    with pytest.raises(FileError, match=r"unsupported shape \(4, 4, 5\)"):
        read_header(tmp_path / "five.npy")
    np.save(tmp_path / "obj.npy", np.array([[None]], dtype=object), allow_pickle=True)
    with pytest.raises(FileError, match="unsupported dtype object"):
        read_header(tmp_path / "obj.npy")


def write_exr(path, channels: dict, tiled: bool = False):
    """An EXR written by the openexr package (what a DCC tool or Poly Haven ships): ``channels`` name -> array."""
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION,
              "type": OpenEXR.tiledimage if tiled else OpenEXR.scanlineimage}
    if tiled:
        header["tiles"] = OpenEXR.TileDescription()
    with OpenEXR.File(header, channels) as exr:
        exr.write(str(path))
    return path


def test_exr_heights_are_read_through_the_openexr_package(tmp_path):
    rng = np.random.default_rng(1)
    height = rng.random((12, 20)).astype(np.float32)
    half = height.astype(np.float16)
    cases = {
        "y_float.exr": ({"Y": height}, height, False),
        "z_half_tiled.exr": ({"Z": half}, half, True),  # any single channel name; tiles read like scan lines
        "rgb_half.exr": ({"R": half, "G": half, "B": half}, half, False),  # equal colour channels: that channel
        "ya.exr": ({"Y": height, "A": np.ones_like(height)}, height, False),
    }
    for name, (channels, expected, tiled) in cases.items():
        path = write_exr(tmp_path / name, channels, tiled)
        header = read_header(path)
        assert (header.format, header.width, header.height) == ("exr", 20, 12), name
        assert header.channel_names == tuple(channels), name
        np.testing.assert_array_equal(read_height(path), expected.astype(np.float32), err_msg=name)
    rgba = write_exr(tmp_path / "rgba.exr", {"R": half, "G": half * 0, "B": half * 0 + 1, "A": half})
    image = read_image(rgba)  # R, G, B, A order (OpenCV's BGR does not apply)
    assert image.shape == (12, 20, 4) and (image[..., 2] == 1).all() and (image[..., 1] == 0).all()
    np.testing.assert_array_equal(read_height(rgba, "r"), half.astype(np.float32))


@pytest.mark.parametrize("channels,flags,kind,reason", [
    ((("Y", EXR_UINT, 1),), 0, b"", "EXR channel 'Y' holds UINT values; expected HALF or FLOAT"),
    ((("Y", EXR_HALF, 2),), 0, b"", "EXR channel 'Y' is subsampled 2x2; expected full resolution"),
    ((("R", EXR_HALF, 1), ("G", EXR_HALF, 1), ("B", EXR_HALF, 1), ("Z", EXR_FLOAT, 1)), 0, b"",
     "EXR channels R, G, B, Z: expected one channel (the height), Y and A, or R, G, B (and A)"),
    ((("Y", EXR_FLOAT, 1),), 0x800, b"deepscanline", "deep EXR data"),
    ((("Y", EXR_FLOAT, 1),), 0x800, b"", "damaged EXR header"),  # the deep flag without what deep data needs
])
def test_an_exr_we_cannot_use_is_refused_from_its_header(tmp_path, channels, flags, kind, reason):
    path = huge_exr(tmp_path / "h.exr", 8, 8, channels, flags, kind)  # no pixel data: nothing past the header
    for read in (read_header, read_image, read_height):
        with pytest.raises(FileError) as error:
            read(path)
        assert error.value.reason.startswith(reason), error.value.reason


def test_bytes_are_read_like_the_file_that_holds_them(tmp_path, good):
    """One reader for paths and bytes in memory (an image a glTF embeds): the same header, the same pixels, and
    problems named by the ImageBytes' name."""
    height = np.linspace(0, 1, 20 * 12, dtype=np.float32).reshape(12, 20)
    files = {**good, "exr": write_exr(tmp_path / "y.exr", {"Y": height})}
    for name, path in files.items():
        memory = ImageBytes(f"mem.{name}", path.read_bytes())
        assert read_header(memory) == read_header(path), name
        assert np.array_equal(read_image(memory), read_image(path)), name
        assert np.array_equal(read_height(path.read_bytes()), read_height(path)), name
    with pytest.raises(FileError) as error:
        read_header(ImageBytes("scene.glb: images[0]", good["png"].read_bytes()[:20]))
    assert str(error.value) == "scene.glb: images[0]: damaged or truncated PNG header; write or download it again"


def test_a_damaged_exr_is_one_line_with_the_decoders_words(tmp_path, capfd):
    """The openexr module prints its warning through Python's stdout and the library its own on stderr; both
    belong in our one line, not on the terminal."""
    good = write_exr(tmp_path / "good.exr", {"Y": np.linspace(0, 1, 64 * 64, dtype=np.float32).reshape(64, 64)})
    data = good.read_bytes()
    cut = tmp_path / "cut.exr"
    cut.write_bytes(data[: len(data) // 2])
    capfd.readouterr()
    with pytest.raises(FileError) as error:
        read_height(cut)
    message = str(error.value)
    assert message.startswith(f"{cut}: cannot decode image (corrupt or unsupported exr; the decoder said: ")
    assert "\n" not in message
    assert capfd.readouterr() == ("", "")


def test_nan_policies_report_how_many_texels_they_replaced(tmp_path, caplog):
    data = np.full((4, 5), 0.5, np.float32)
    data[0, 0], data[1, 2], data[3, 4] = np.nan, np.inf, -np.inf
    np.save(tmp_path / "n.npy", data)
    for policy, what in (("zero", "0"), ("nearest", "the nearest finite value")):
        caplog.clear()
        out = read_height(tmp_path / "n.npy", nan_policy=policy)
        assert np.isfinite(out).all()
        assert f"n.npy: 3 of 20 texels were NaN/inf; replaced ({policy}: {what})" in caplog.text
        assert [(r.name, r.levelname) for r in caplog.records] == [("wgpuviewer.images", "WARNING")]


def _damaged(tmp_path, fmt: str):
    """A small PNG whose compressed data is damaged (its signature, header and CRCs intact), or a JPEG whose scan
    data is: libpng cannot decode the one, libjpeg decodes the other with a complaint."""
    rng = np.random.default_rng(0)
    if fmt == "png":
        pixels = (np.arange(32 * 32).reshape(32, 32) % 251).astype(np.uint8)
        ok, data = cv2.imencode(".png", pixels)
        data = bytearray(data.tobytes())
        at = data.find(b"IDAT") + 10
        data[at] ^= 0xFF
        start = data.find(b"IDAT")
        length = struct.unpack(">I", data[start - 4:start])[0]
        data[start + 4 + length:start + 8 + length] = struct.pack(">I", zlib.crc32(data[start:start + 4 + length]))
    else:
        ok, data = cv2.imencode(".jpg", rng.integers(0, 255, (64, 64, 3), dtype=np.uint8))
        data = bytearray(data.tobytes())
        data[len(data) // 2:len(data) // 2 + 40] = b"\xff\x00" * 20
    path = tmp_path / f"damaged.{fmt}"
    path.write_bytes(bytes(data))
    return path


def test_a_decoder_complaint_is_part_of_our_one_line_not_a_line_of_its_own(tmp_path, capfd, caplog):
    """libpng printed `libpng error: ...` on stderr ahead of our error line; libjpeg printed `Corrupt JPEG data`
    and the damaged image was taken silently."""
    png = _damaged(tmp_path, "png")
    with pytest.raises(FileError) as error:
        read_image(png)
    assert str(error.value).startswith(f"{png}: cannot decode image (corrupt or unsupported png; the decoder said: "
                                       "libpng error:"), str(error.value)
    assert "\n" not in str(error.value)
    capfd.readouterr()
    assert maptools_cli.main(["generate", "normal", str(png), "-o", str(tmp_path / "n.png"), "--backend", "cpu"]) == 2
    assert capfd.readouterr().err.splitlines() == [f"maptools: error: {error.value}"]
    jpeg = _damaged(tmp_path, "jpeg")
    assert read_image(jpeg).shape == (64, 64, 3)
    err = capfd.readouterr().err.splitlines()  # only our own lines (a CLI's handler prints the warning as one)
    assert not [line for line in err if line.startswith(("libpng", "Corrupt JPEG"))], err
    warnings = [r.getMessage() for r in caplog.records if r.name == "wgpuviewer.images"]
    assert len(warnings) == 1 and warnings[0].startswith(f"{jpeg}: decoded, but the jpeg decoder said: Corrupt JPEG "
                                                         "data"), warnings


def test_only_native_output_during_a_decode_is_taken(tmp_path, capfd, monkeypatch):
    """Another thread's Python stderr (a warning) waits for the decode and then reaches the terminal; terminal
    redraws (a progress bar) pass on; what the decoder writes on file descriptor 2 is taken."""
    import os
    import sys
    import threading

    from wgpuviewer.core import native_output

    good = tmp_path / "good.png"
    cv2.imwrite(str(good), np.zeros((4, 4), np.uint8))
    other = threading.Thread(target=lambda: print("a warning of another thread", file=sys.stderr, flush=True))

    def chatty(buf, flags):
        other.start()  # it prints while the decode holds the descriptor
        os.write(2, b"libfoo warning: something odd\n")
        os.write(2, b"\r 40%|####      |")
        return cv2.imdecode(buf, flags)

    monkeypatch.setattr(sys, "stderr", sys.__stderr__)  # as in a CLI process: Python's stderr is descriptor 2
    said = []
    with native_output.native_stderr(said):
        chatty(np.fromfile(good, np.uint8), cv2.IMREAD_UNCHANGED)
    other.join(timeout=10)
    err = capfd.readouterr().err
    assert said == ["libfoo warning: something odd"]
    # the two writers are not ordered against each other: each arrives whole
    assert "a warning of another thread" in err and "\r 40%|####      |" in err and "libfoo" not in err
    assert sys.stderr is sys.__stderr__


@pytest.mark.parametrize("case", ["dangling", "loop"])
def test_a_broken_link_is_named_as_one(tmp_path, case):
    path = tmp_path / "height.png"
    if case == "dangling":
        path.symlink_to(tmp_path / "gone.png")
        reason = f"broken link to {tmp_path / 'gone.png'} (the target does not exist); fix or remove the link"
    else:
        path.symlink_to("height.png")
        reason = "symbolic link loop (the link leads back to itself); fix or remove the link"
    for read in (read_header, read_image, read_height):
        with pytest.raises(FileError) as error:
            read(path)
        assert error.value.reason == reason
