"""Turntables: a scene filmed by a camera orbiting its target, one full turn in N frames, written as an animated GIF
(pillow) or an MP4 (H.264 through the ffmpeg that imageio-ffmpeg ships), atomically. Frames stream: an MP4's go to
ffmpeg as they are rendered, a GIF's are held quantised (one byte a pixel) until pillow encodes them.

The orbit turns the whole camera (position and up vector) about the vertical axis (+y, the viewer's up) through the
camera's target, counter-clockwise seen from above: frame 0 is the camera itself and frame N would be it again, so
the clip loops without a seam. The lights stay where the scene puts them. The MP4 writer is an optional dependency
(``pip install 'wgpuviewer[turntable]'``); every check (suffix, frame count, size, memory, a writer missing) comes
before the GPU starts.
"""

from __future__ import annotations

import io
import math
import tempfile
from collections.abc import Callable, Iterable, Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import write_bytes
from wgpuviewer.scene import Camera

from .output import mode_picture
from .renderer import DrawConfig, Renderer

#: What each suffix is written with: (the module imported, the package that provides it).
WRITERS = {".gif": ("PIL", "pillow"), ".mp4": ("imageio_ffmpeg", "imageio-ffmpeg")}
#: Frames per second of both formats (a GIF's delay is whole hundredths of a second: 4 at 25 fps).
FPS = 25
#: A turn needs two frames to move at all; 3600 is two and a half minutes at 25 fps.
FRAME_RANGE = (2, 3600)
#: The GIF writer holds every frame in memory until it encodes them; a larger clip is refused up front.
GIF_MEMORY_LIMIT = 2 << 30
#: Bytes a GIF turntable holds per pixel of every frame at its peak: the quantised frames (one byte), the encoded
#: clip and pillow's working copies (measured: 3.9 for frames of noise, the largest GIFs; ``tests/relief/
#: test_turntable.py`` holds the peak under this).
GIF_BYTES_PER_PIXEL = 5
INSTALL = "pip install 'wgpuviewer[turntable]'"


def check_turntable(path, frames: int, size: tuple[int, int], option: str = "--orbit") -> None:
    """A UserError naming ``option`` (the frame count), ``-o`` or ``--size`` for a turntable that cannot be written;
    nothing is rendered or started."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in WRITERS:
        raise UserError(f"-o {path}: {option} writes an animation; use .gif or .mp4 (got {path.suffix or 'no suffix'!r})")
    lo, hi = FRAME_RANGE
    if not lo <= frames <= hi:
        raise UserError(f"{option} {frames}: expected {lo} to {hi} frames for one full turn")
    w, h = size
    if suffix == ".mp4" and (w % 2 or h % 2):
        raise UserError(f"--size {w}x{h}: an MP4 (H.264, 4:2:0) needs an even width and height, e.g. "
                        f"{w + w % 2}x{h + h % 2}")
    held = w * h * GIF_BYTES_PER_PIXEL * frames
    if suffix == ".gif" and held > GIF_MEMORY_LIMIT:
        raise UserError(f"{option} {frames} at --size {w}x{h}: a GIF holds every frame in memory "
                        f"({held / 2**30:.1f} GiB, more than {GIF_MEMORY_LIMIT / 2**30:g} GiB); use fewer frames, "
                        "a smaller --size or .mp4")
    module, package = WRITERS[suffix]
    try:
        __import__(module)
    except ImportError:
        raise UserError(f"-o {path}: writing {suffix} needs the {package} package: {INSTALL}") from None


def orbit_cameras(camera: Camera, frames: int) -> list[Camera]:
    """``frames`` cameras evenly spaced over one turn about the vertical axis through ``camera.target``."""
    target = np.asarray(camera.target, np.float64)
    offset = np.asarray(camera.position, np.float64) - target
    up = np.asarray(camera.up, np.float64)
    cameras = []
    for i in range(frames):
        angle = 2.0 * math.pi * i / frames
        c, s = math.cos(angle), math.sin(angle)
        # Rotation about +y by ``angle``: counter-clockwise seen from above (x towards -z).
        turn = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        cameras.append(replace(camera, position=tuple(float(x) for x in target + turn @ offset),
                               up=tuple(float(x) for x in turn @ up)))
    return cameras


def turntable_pictures(renderer: Renderer, draw: DrawConfig, camera: Camera, size: tuple[int, int], frames: int,
                       mode: str = "color", progress: Callable[[int, int], None] | None = None) -> Iterator[np.ndarray]:
    """The (H, W, 3) uint8 pictures of ``mode`` along the orbit, rendered one at a time; ``progress(done, total)``
    after each."""
    for done, frame_camera in enumerate(orbit_cameras(camera, frames), 1):
        yield mode_picture(renderer.render(draw, size, frame_camera, mode), mode)
        if progress is not None:
            progress(done, frames)


def write_turntable(path, pictures: Iterable[np.ndarray], size: tuple[int, int]) -> None:
    """Write ``pictures`` (each (H, W, 3) uint8, ``size`` = (W, H)) to ``path`` (.gif or .mp4, ``check_turntable``
    first) at ``FPS``; a reader never sees a partial file."""
    path = Path(path)
    if path.suffix.lower() == ".gif":
        write_bytes(path, _gif(pictures))
    else:
        write_bytes(path, _mp4(pictures, size))


def _gif(pictures: Iterable[np.ndarray]) -> bytes:
    from PIL import Image

    # Each picture is quantised to its own 256-colour palette as it comes (what pillow's GIF writer does to an RGB
    # frame), so the clip is held at one byte a pixel (GIF_BYTES_PER_PIXEL), never as RGB frames.
    frames = [Image.fromarray(picture).convert("P", palette=Image.Palette.ADAPTIVE) for picture in pictures]
    out = io.BytesIO()
    # loop=0: play forever.
    frames[0].save(out, format="GIF", save_all=True, append_images=frames[1:], duration=1000 / FPS, loop=0)
    return out.getvalue()


def _mp4(pictures: Iterable[np.ndarray], size: tuple[int, int]) -> bytes:
    import imageio_ffmpeg

    # ffmpeg writes by file name: into a private folder, then the bytes go to ``path`` atomically. Frames are
    # streamed to ffmpeg as they are rendered (nothing held); macro_block_size 2 keeps the size (4:2:0 needs even
    # sides, checked up front) where the default 16 would rescale.
    with tempfile.TemporaryDirectory(prefix="wgpuviewer-turntable-") as folder:
        clip = Path(folder) / "turntable.mp4"
        writer = imageio_ffmpeg.write_frames(str(clip), size, fps=FPS, codec="libx264", pix_fmt_out="yuv420p",
                                             macro_block_size=2, ffmpeg_log_level="error")
        writer.send(None)  # starts ffmpeg
        try:
            for picture in pictures:
                writer.send(np.ascontiguousarray(picture))
        finally:
            writer.close()
        return clip.read_bytes()
