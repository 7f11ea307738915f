"""Turntables (``render --orbit N -o out.gif|out.mp4``): the orbit's cameras, the checks made before the GPU starts,
atomic writes, and tiny GIF and MP4 clips read back frame by frame."""

from __future__ import annotations

import math
import subprocess
import sys

import cv2
import numpy as np
import pytest

from wgpuviewer import cli
from wgpuviewer.core.errors import UserError
from wgpuviewer.relief import turntable
from wgpuviewer.scene import Camera

CAMERA = Camera(position=(0.3, 1.4, 3.2), target=(0.1, 0.2, -0.4), up=(0.0, 1.0, 0.0), fov=50.0)


def test_the_orbit_turns_the_camera_once_about_the_vertical_through_its_target():
    cameras = turntable.orbit_cameras(CAMERA, 8)
    assert len(cameras) == 8 and cameras[0] == CAMERA  # frame 0 is the camera itself
    target = np.array(CAMERA.target)
    start = np.array(CAMERA.position) - target
    for i, c in enumerate(cameras):
        offset = np.array(c.position) - target
        assert c.target == CAMERA.target and (c.fov, c.near, c.far) == (CAMERA.fov, CAMERA.near, CAMERA.far)
        assert offset[1] == pytest.approx(start[1])  # same height
        assert np.linalg.norm(offset[[0, 2]]) == pytest.approx(np.linalg.norm(start[[0, 2]]))  # same radius
        turned = math.atan2(offset[0], offset[2]) - math.atan2(start[0], start[2])
        # i/8 of a turn, counter-clockwise seen from above (+y): the offset's azimuth atan2(x, z) grows
        assert math.remainder(turned - 2 * math.pi * i / 8, 2 * math.pi) == pytest.approx(0, abs=1e-12)
    # the up vector turns with the camera: a camera looking straight down spins instead of standing still
    down = Camera(position=(0.0, 2.0, 0.0), target=(0.0, 0.0, 0.0), up=(0.0, 0.0, -1.0))
    quarter = turntable.orbit_cameras(down, 4)[1]
    assert quarter.position == pytest.approx((0.0, 2.0, 0.0)) and quarter.up == pytest.approx((-1.0, 0.0, 0.0))


@pytest.mark.parametrize("path, frames, size, message", [
    ("t.png", 4, (32, 24), "-o t.png: --orbit writes an animation; use .gif or .mp4 (got '.png')"),
    ("t", 4, (32, 24), "use .gif or .mp4 (got 'no suffix')"),
    ("t.gif", 1, (32, 24), "--orbit 1: expected 2 to 3600 frames for one full turn"),
    ("t.mp4", 3601, (32, 24), "--orbit 3601: expected 2 to 3600 frames"),
    ("t.mp4", 4, (33, 24), "--size 33x24: an MP4 (H.264, 4:2:0) needs an even width and height, e.g. 34x24"),
    ("t.gif", 600, (1280, 720), "--orbit 600 at --size 1280x720: a GIF holds every frame in memory (2.6 GiB"),
])
def test_a_turntable_that_cannot_be_written_is_refused_up_front(path, frames, size, message):
    with pytest.raises(UserError) as error:
        turntable.check_turntable(path, frames, size)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_a_missing_writer_names_the_package_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # import fails as if not installed
    with pytest.raises(UserError, match=r"writing \.mp4 needs the imageio-ffmpeg package: pip install "
                                        r"'wgpuviewer\[turntable\]'"):
        turntable.check_turntable("t.mp4", 4, (32, 24))
    turntable.check_turntable("t.gif", 4, (32, 24))  # the GIF writer is another package


@pytest.mark.parametrize("suffix", [".gif", ".mp4"])
def test_a_failure_while_rendering_leaves_no_file(tmp_path, suffix):
    def pictures():
        yield np.zeros((24, 32, 3), np.uint8)
        raise UserError("the adapter is gone")

    out = tmp_path / f"t{suffix}"
    with pytest.raises(UserError, match="the adapter is gone"):
        turntable.write_turntable(out, pictures(), (32, 24))
    assert list(tmp_path.iterdir()) == []


#: A GIF clip's peak memory, measured in a process of its own: 30 frames of 200x150 noise (the largest GIF).
GIF_PEAK = """
import resource, sys
import numpy as np
from wgpuviewer.relief import turntable
w, h, n = 200, 150, 30
noise = np.random.default_rng(0).integers(0, 255, (h, w, 3), dtype=np.uint8)
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
turntable.write_turntable(sys.argv[1], (np.roll(noise, i, axis=1) for i in range(n)), (w, h))
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 - before, w * h * n)
"""


def test_a_gif_turntable_stays_within_the_memory_it_is_checked_against(tmp_path):
    """check_turntable refuses a GIF by GIF_BYTES_PER_PIXEL: the writer's real peak stays under it."""
    result = subprocess.run([sys.executable, "-c", GIF_PEAK, str(tmp_path / "t.gif")], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    peak, pixels = (int(x) for x in result.stdout.split())
    assert peak < turntable.GIF_BYTES_PER_PIXEL * pixels, (peak / pixels)
    assert (tmp_path / "t.gif").stat().st_size > pixels  # the clip was written, each frame's noise kept


def gif_frames(path) -> np.ndarray:
    import imageio.v3 as iio

    return iio.imread(path, index=None)


def mp4_frames(path) -> tuple[dict, np.ndarray]:
    import imageio_ffmpeg

    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    w, h = meta["size"]
    return meta, np.stack([np.frombuffer(f, np.uint8).reshape(h, w, 3) for f in reader])


def test_render_orbit_writes_gif_and_mp4_turntables(tmp_path, capsys, adapter):
    still = tmp_path / "still.png"
    base = ["render", "--technique", "basic", "--size", "32x24"]
    assert cli.main([*base, "-o", str(still)]) == 0
    assert cli.main([*base, "--orbit", "4", "-o", str(tmp_path / "t.gif")]) == 0
    assert cli.main([*base, "--orbit", "4", "-o", str(tmp_path / "t.mp4")]) == 0
    assert capsys.readouterr().out.split() == [str(tmp_path / n) for n in ("still.png", "t.gif", "t.mp4")]
    first = cv2.cvtColor(cv2.imread(str(still)), cv2.COLOR_BGR2RGB).astype(int)

    gif = gif_frames(tmp_path / "t.gif")
    assert gif.shape == (4, 24, 32, 3)
    assert len({frame.tobytes() for frame in gif}) == 4  # four distinct views
    assert np.abs(gif[0].astype(int) - first).mean() < 3  # frame 0 is the scene camera's view (palette rounding)

    meta, mp4 = mp4_frames(tmp_path / "t.mp4")
    assert mp4.shape == (4, 24, 32, 3) and meta["fps"] == turntable.FPS
    assert len({frame.tobytes() for frame in mp4}) == 4
    assert np.abs(mp4[0].astype(int) - first).mean() < 12  # H.264 at this size is lossy, but it is the same view
    # each frame is nearest to its own GIF frame: the same orbit, in order
    for i, frame in enumerate(mp4.astype(int)):
        assert int(np.argmin([np.abs(frame - g).mean() for g in gif.astype(int)])) == i


def test_render_orbit_bad_input_is_one_line_before_the_gpu(tmp_path, capsys, monkeypatch):
    def no_gpu(*args, **kwargs):
        raise AssertionError("the GPU was started")

    monkeypatch.setattr("wgpuviewer.core.gpu.get_gpu", no_gpu)
    for argv, message in [
        (["--orbit", "4", "-o", str(tmp_path / "t.png")], "--orbit writes an animation; use .gif or .mp4"),
        (["--orbit", "0", "-o", str(tmp_path / "t.gif")], "--orbit 0: expected 2 to 3600 frames"),
        (["-o", str(tmp_path / "t.gif")], "unknown output type '.gif'; use .png (image) or .npy (raw float32 data), "
                                          "or .gif or .mp4 with --orbit N"),
        (["--orbit", "4", "--size", "31x24", "-o", str(tmp_path / "t.mp4")], "--size 31x24: an MP4"),
    ]:
        assert cli.main(["render", *argv]) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and message in err[0], err
    assert list(tmp_path.iterdir()) == []
