"""The `render` command's way to the Python API (``wgpuviewer.api``), which the viewer's offscreen fallback takes
too: the options read into the API's arguments (``prepare_render``), the prepared render written as a file or a
turntable, and the API's errors worded with the options that set its arguments (``api_errors``, at the CLI's
edge: the API names its own arguments).

May import: anything (a part of the CLI).
"""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path

from wgpuviewer.core.commands import comma_numbers
from wgpuviewer.core.errors import UserError

#: The options of `render` that set the Python API's arguments (wgpuviewer.api), by argument: the names its
#: messages give them (``api_errors``).
RENDER_OPTIONS = {"position": "--camera", "target": "--target", "fov": "--fov", "view_angle": "--view-angle",
                  "height_scale": "--height-scale", "uv_scale": "--uv-scale", "size": "--size", "mode": "--mode",
                  "technique": "--technique", "filter": "--filter", "derivatives": "--derivatives",
                  "material": "--material", "shadows": "--shadows", "backend": "--backend"}


def option_label(option: str, value) -> str:
    """How a message shows an option's value: a name as ``--technique = 'nope'``, numbers as typed (``--camera
    0,1,2``, ``--fov 180``)."""
    if isinstance(value, str):
        return f"{option} = {value!r}"
    if isinstance(value, (tuple, list)):
        return f"{option} {','.join(f'{float(x):g}' for x in value)}"
    return f"{option} {value:g}" if isinstance(value, float) else f"{option} {value}"


@contextlib.contextmanager
def api_errors():
    """Errors of the Python API (its ``ArgumentError``s, a frame too large: ``FrameError``) as UserErrors naming
    the options of `render` (``RENDER_OPTIONS``)."""
    from wgpuviewer.api import ArgumentError
    from wgpuviewer.relief.targets import FrameError

    try:
        yield
    except ArgumentError as error:
        raise UserError(error.worded(RENDER_OPTIONS, option_label)) from None
    except FrameError as error:
        raise UserError(error.named("--size")) from None


def prepare_render(args, scene, size: tuple[int, int]):
    """``api.prepare`` of ``scene`` (the scene argument with ``--material``) with ``--height-scale`` and
    ``--uv-scale``, the camera of ``--camera``, ``--target``, ``--fov`` and ``--view-angle``, ``--technique``, the
    filtering options and ``--backend``: the Python API checks and builds them all, so a render from the command
    line and one from Python agree. The CLI renders once per process: a renderer of its own, not the API's kept
    ones."""
    from wgpuviewer.api import CameraSpec, prepare

    tiling = comma_numbers(args.uv_scale, "--uv-scale", "2 or 2,1")
    if tiling is not None and len(tiling) not in (1, 2):
        raise UserError(f"--uv-scale {args.uv_scale!r}: expected one number (both directions) or U,V, e.g. 2,1")
    spec = CameraSpec(position=point_option(args.camera, "--camera"), target=point_option(args.target, "--target"),
                      fov=args.fov, view_angle=args.view_angle)
    return prepare(scene, args.technique, size, spec, height_scale=args.height_scale,
                   uv_scale=tiling if tiling is None or len(tiling) == 2 else tiling[0], filter=args.filter,
                   derivatives=args.derivatives, shadows=args.shadows, backend=args.backend, keep=False)


def save_render(out: Path, prepared, mode: str, alpha: bool = False) -> None:
    """One frame of a prepared render (``api.prepare``) into ``out`` (.png or .npy; ``alpha``: transparent where
    nothing was drawn, ``relief.output``)."""
    from wgpuviewer.relief.output import save_output

    save_output(out, prepared.image(mode), mode, alpha)


def render_orbit(out: Path, prepared, mode: str, frames: int) -> None:
    """A turntable (``relief.turntable``): ``frames`` renders of one turn of the prepared camera about its target,
    written to ``out`` (.gif or .mp4, checked by ``check_turntable`` first)."""
    from tqdm import tqdm

    from wgpuviewer.relief.turntable import turntable_pictures, write_turntable

    with tqdm(total=frames, desc="turntable", unit="frame", file=sys.stderr, disable=None, leave=False) as bar:
        pictures = turntable_pictures(prepared.renderer, prepared.draw, prepared.camera, prepared.size, frames,
                                      mode, progress=lambda done, total: bar.update(1))
        write_turntable(out, pictures, prepared.size)


def point_option(text: str | None, option: str) -> tuple[float, float, float] | None:
    """``X,Y,Z`` as three numbers (None when the option was not given)."""
    numbers = comma_numbers(text, option, "0,1.4,3.2")
    if numbers is not None and len(numbers) != 3:
        raise UserError(f"{option} {text!r}: expected three numbers X,Y,Z, e.g. 0,1.4,3.2")
    return None if numbers is None else tuple(numbers)
