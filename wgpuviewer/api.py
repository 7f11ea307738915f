"""The Python API: ``render`` (a scene drawn offscreen into a numpy array), ``view`` (the interactive viewer as a
Jupyter widget), and ``prepare`` (everything ``render`` does before it draws), through which ``wgpuviewer render``
draws too: one path for a render. The camera a render uses comes from ``camera_for`` (a ``CameraSpec``), a
material's relief settings from ``with_relief``.

Arguments are checked before the GPU starts (``view`` checks them as ``render`` does); every error the API raises
for its input is a ValueError of one line: an ``ArgumentError`` naming the argument (``backend = 'metal': ...``), which
keeps the argument, the value and the reason apart so the CLI words it with its options, or an ``ApiError`` for a
problem found in a file (a scene file, a texture: the file and key named, as in the CLI; ``_user_errors``). The
first GPU use is as quiet as the CLI's: no driver line about ``XDG_RUNTIME_DIR`` (``core.gpu``); a software adapter
is named once on stderr.

Threads: ``render``, ``prepare`` and ``Prepared.image`` may be called from several threads at once. The kept
renderers and devices are shared under one lock; a renderer's maps are built once (``Renderer.prepare``) and each
frame is drawn and read back under its device's lock (``Renderer.render``, ``Gpu.lock``): frames on one device
are drawn one at a time, each with its own camera and settings.

The subject of a scene: its first plane (where ``--material`` shows a folder), or its first object when it has
no plane. ``view_angle``, ``height_scale`` and ``uv_scale`` are about the subject.

Imports: ``core``, the scene modules, ``relief`` and (for ``view``) ``viewer``; never the measuring rooms. The CLI
imports it (``render`` and the offscreen ``view``); ``wgpuviewer/__init__`` exports its public names, loading it on
first use.
"""

from __future__ import annotations

import contextlib
import math
import os
import threading
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from . import camera as cam
from .core.errors import ApiError, InputError, NoAdapterError, UserError
from .scene import (
    SHADOW_MODES,
    Camera,
    Scene,
    default_scene_path,
    load_scene,
    uv_scale_problem,
    with_folder_material,
)
from .scene.table import show_value as _show

if TYPE_CHECKING:
    from .relief.renderer import DrawConfig, OffscreenImage, Renderer

#: The default frame size of ``render``: the CLI's (``cli.DEFAULT_SIZE``; a test holds them equal, the CLI cannot
#: import this module before its process is prepared).
DEFAULT_SIZE = (1280, 720)
#: ``view``'s default widget size in logical pixels: a notebook cell's width.
DEFAULT_WIDGET_SIZE = (640, 360)
#: Renderers ``render`` keeps: repeated renders of a scene reuse its textures, maps and pipelines; beyond this many
#: the least recently used one is dropped (its GPU memory released).
MAX_RENDERERS = 4

#: How messages name each argument (``ArgumentError``).
API_NAMES = {"position": "camera.position", "target": "camera.target", "fov": "camera.fov",
             "view_angle": "camera.view_angle", "height_scale": "height_scale", "uv_scale": "uv_scale",
             "size": "size", "mode": "mode", "technique": "technique", "filter": "filter", "derivatives": "derivatives",
             "material": "material", "shadows": "shadows", "backend": "backend"}

#: The subject's surface normal in its object's frame (before rotation): a plane's and a box's top face, a quad's
#: front.
SURFACE_NORMALS = {"plane": (0.0, 1.0, 0.0), "box": (0.0, 1.0, 0.0), "quad": (0.0, 0.0, 1.0)}


@dataclass(frozen=True)
class CameraSpec:
    """What a render changes of the scene's camera; None keeps the scene's value.

    ``position``, ``target``: points (x, y, z); ``fov``: vertical field of view in degrees, 1 to 179 (exclusive);
    ``view_angle``: degrees from the subject's surface normal, 0 (looking straight down onto the surface) up to
    90 (grazing, exclusive), instead of ``position``: the camera looks at the target from the scene camera's
    distance to it, along a direction at ``view_angle`` from the normal, on the side of the surface the scene
    camera sees it from. For a flat surface that is the angle at which the view ray through the target meets it,
    wherever it does. The camera's ``up`` stays the scene camera's; a view along it (straight down) gets the
    scene camera's view direction as up instead. ``camera_for`` checks every value.
    """

    position: tuple[float, float, float] | None = None
    target: tuple[float, float, float] | None = None
    fov: float | None = None
    view_angle: float | None = None

    @classmethod
    def of(cls, value) -> CameraSpec:
        """A CameraSpec from None, a CameraSpec or a dict of its fields (unknown keys are an InputError)."""
        if value is None:
            return cls()
        if isinstance(value, cls):
            return value
        if isinstance(value, dict):
            names = [f.name for f in fields(cls)]
            unknown = [key for key in value if key not in names]
            if unknown:
                raise InputError(f"camera: unknown key {unknown[0]!r}; expected some of {', '.join(names)}")
            return cls(**value)
        raise InputError(f"camera = {_show(value)}: expected None, a dict of {', '.join(f.name for f in fields(cls))}"
                         " or a wgpuviewer.CameraSpec")


class ArgumentError(InputError):
    """A bad value of one argument: ``argument`` (a key of ``API_NAMES``), the ``value`` given and ``reason``, in
    which ``{key}`` names another argument. The message names them as the API does (``camera.position = (0, 0, 0):
    the camera is at its target; ...``); a caller that names them otherwise (the CLI: its options) words it again
    with ``worded``."""

    def __init__(self, argument: str, value, reason: str):
        self.argument, self.value, self.reason = argument, value, reason
        super().__init__(self.worded(API_NAMES, lambda name, value: f"{name} = {_show(value)}"))

    def worded(self, names: dict, label) -> str:
        """The message naming the arguments by ``names``, the bad one as ``label(its name, value)``."""
        return f"{label(names[self.argument], self.value)}: {self.reason.format_map(names)}"


def _number(key: str, value, lo: float, hi: float, lo_open: bool, hi_open: bool) -> float:
    """A real number within lo..hi (open ends as given; hi may be inf): an ArgumentError naming ``key`` otherwise."""
    if math.isinf(hi):
        expected = f"a number above {lo:g}" if lo_open else f"a number of at least {lo:g}"
    else:
        expected = f"a number from {lo:g}{' (exclusive)' if lo_open else ''} to {hi:g}{' (exclusive)' if hi_open else ''}"
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ArgumentError(key, value, f"expected {expected}")
    x = float(value)
    inside = (x > lo if lo_open else x >= lo) and (x < hi if hi_open else x <= hi)
    if not (math.isfinite(x) and inside):
        raise ArgumentError(key, value, f"out of range, expected {expected}")
    return x


def _point(key: str, value) -> np.ndarray:
    """Three finite numbers as a float64 vector: an ArgumentError naming ``key`` otherwise."""
    try:
        p = np.asarray(value, np.float64)
    except (TypeError, ValueError):
        p = None
    if p is None or p.shape != (3,) or isinstance(value, (str, bytes)):
        raise ArgumentError(key, value, "expected a point of 3 numbers x, y, z")
    if not np.isfinite(p).all():
        raise ArgumentError(key, value, "expected finite numbers")
    return p


def _entry(key: str, name, get):
    """The registry entry ``get(name)`` (techniques, filters, derivative sources): an ArgumentError naming ``key``
    with the registry's reason otherwise."""
    try:
        return get(name, key)
    except UserError as error:
        reason = str(error).removeprefix(f"{key} = {name!r}: ")
        raise ArgumentError(key, name, reason.replace("{", "{{").replace("}", "}}")) from None


def subject(scene: Scene) -> int:
    """Index of the scene's subject: its first plane (where ``--material`` shows a folder), else its first object."""
    return next((i for i, o in enumerate(scene.objects) if o.type == "plane"), 0)


def surface_normal(scene: Scene) -> np.ndarray:
    """The world-space unit normal of the subject's surface (``SURFACE_NORMALS``, rotated with its object)."""
    obj = scene.objects[subject(scene)]
    return cam.normalize(cam.rotation_xyz(obj.rotation)[:3, :3] @ np.asarray(SURFACE_NORMALS[obj.type]))


def _perpendicular(v: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """``v`` without its component along the unit vector ``axis``."""
    return v - np.dot(v, axis) * axis


def camera_for(scene: Scene, spec: CameraSpec | dict | None = None) -> Camera:
    """The camera of a render: the scene's, changed by ``spec`` (see ``CameraSpec``), every value checked (an
    ArgumentError). The one way ``render`` (and so ``wgpuviewer render --camera/--target/--fov/--view-angle``)
    and ``view`` build it."""
    spec = CameraSpec.of(spec)
    base = scene.camera
    if spec.position is not None and spec.view_angle is not None:
        raise ArgumentError("view_angle", spec.view_angle,
                            "{position} places the camera too; give one of {position} and {view_angle}")
    target = _point("target", spec.target) if spec.target is not None else np.asarray(base.target)
    fov = _number("fov", spec.fov, 1, 179, True, True) if spec.fov is not None else base.fov
    if spec.view_angle is not None:
        angle = math.radians(_number("view_angle", spec.view_angle, 0, 90, False, True))
        object_type = scene.objects[subject(scene)].type
        if object_type not in SURFACE_NORMALS:  # a curved or mesh subject has no one normal to measure the angle from
            raise ArgumentError("view_angle", spec.view_angle, f"the scene's subject (its first plane, else its "
                                f"first object) is a {object_type}, which has no single surface normal; expected a subject "
                                f"of type {', '.join(SURFACE_NORMALS)}, or give {{position}}")
        normal = surface_normal(scene)
        seen_from = np.asarray(base.position) - target
        distance = float(np.linalg.norm(seen_from))
        side = _perpendicular(seen_from, normal)  # the scene camera's side of the surface, along it
        if np.linalg.norm(side) < 1e-9 * max(distance, 1e-30):  # the scene camera is on the normal: its up
            side = _perpendicular(np.asarray(base.up), normal)
        position = target + distance * (math.cos(angle) * normal + math.sin(angle) * cam.normalize(side))
        key = "view_angle"
    elif spec.position is not None:
        position, key = _point("position", spec.position), "position"
    else:
        position, key = np.asarray(base.position), "target" if spec.target is not None else None
    view = target - position
    distance = float(np.linalg.norm(view))
    if key is not None:  # the scene checked its own camera
        if distance < 1e-9:
            raise ArgumentError(key, getattr(spec, key),
                                "the camera is at its target; expected {position} and {target} apart")
        if distance >= base.far:
            raise ArgumentError(key, getattr(spec, key), f"the target is {distance:.4g} from the camera, beyond "
                                f"its far plane at {base.far:g} (the scene's camera.far); move them closer")
    forward = view / distance
    up = np.asarray(base.up)
    if np.linalg.norm(np.cross(up, forward)) < 1e-6:  # looking along up: the scene camera's view direction is up
        up = cam.normalize(_perpendicular(cam.normalize(np.subtract(base.target, base.position)), forward))
    return replace(base, position=tuple(float(x) for x in position), target=tuple(float(x) for x in target),
                   up=tuple(float(x) for x in up), fov=fov)


def with_relief(scene: Scene, height_scale=None, uv_scale=None) -> Scene:
    """``scene`` with the subject's material given a relief depth (``height_scale``, UV units, 0 to 1) and a
    tiling (``uv_scale``: one number for both directions, or (u, v), each above 0); None keeps the material's.
    Every object of that material shows the change. Checked as a scene's values are (the texel-coordinate limit
    included): an ArgumentError naming the setting."""
    if height_scale is None and uv_scale is None:
        return scene
    name = scene.objects[subject(scene)].material
    material = scene.materials[name]
    if height_scale is not None:
        material = replace(material, height_scale=_number("height_scale", height_scale, 0, 1, False, False))
    if uv_scale is not None:
        pair = (uv_scale, uv_scale) if np.ndim(uv_scale) == 0 else uv_scale
        if isinstance(pair, (str, bytes)) or np.ndim(pair) != 1 or len(pair) != 2:
            raise ArgumentError("uv_scale", uv_scale, "expected a number or two (u, v)")
        tiling = tuple(_number("uv_scale", x, 0, math.inf, True, True) for x in pair)
        problem = uv_scale_problem(material, tiling)
        if problem:
            raise ArgumentError("uv_scale", uv_scale, problem.replace("{", "{{").replace("}", "}}"))
        material = replace(material, uv_scale=tiling)
    return replace(scene, materials={**scene.materials, name: material})


@contextlib.contextmanager
def _user_errors():
    """What a call of the API raises for its input is a ValueError: a UserError from below (a scene file, a texture,
    a map too large) is raised again as an ``ApiError`` with its message; ValueErrors pass as they are."""
    try:
        yield
    except ValueError:
        raise
    except UserError as error:
        raise ApiError(str(error)) from error


@_user_errors()
def scene_of(scene=None, material=None, height_scale=None, uv_scale=None) -> Scene:
    """The Scene a call means: ``scene`` (None: the default scene; a path to a scene TOML; a Scene), with the
    material folder ``material`` on its first plane, and the subject's relief settings (``with_relief``)."""
    if scene is None:
        scene = load_scene(default_scene_path())
    elif isinstance(scene, (str, Path)):
        scene = load_scene(Path(scene).expanduser())
    elif not isinstance(scene, Scene):
        raise InputError(f"scene = {_show(scene)}: expected None (the default scene), a scene .toml path or a "
                         "wgpuviewer.scene.Scene")
    if material is not None:
        scene = _with_material(scene, material)
    return with_relief(scene, height_scale, uv_scale)


def _with_material(scene: Scene, material) -> Scene:
    """``with_folder_material`` of the folder ``material``; its problems (worded for ``--material DIR``) are an
    ArgumentError naming ``material``."""
    if isinstance(material, bool) or not isinstance(material, (str, os.PathLike)):
        raise ArgumentError("material", material, "expected a material folder's path (a str or a pathlib.Path)")
    folder = Path(material).expanduser()
    try:
        return with_folder_material(scene, folder)
    except UserError as error:
        reason = str(error).removeprefix(f"--material {folder}: ")
        raise ArgumentError("material", material, reason.replace("{", "{{").replace("}", "}}")) from None


def _backend(backend) -> str | None:
    """A backend name (None: the environment's, else auto): an ArgumentError naming ``backend`` otherwise."""
    from .core.gpu import BACKEND_CHOICES

    if backend is not None and (not isinstance(backend, str) or backend.strip().lower() not in BACKEND_CHOICES):
        raise ArgumentError("backend", backend, f"expected one of {', '.join(BACKEND_CHOICES)}, or None")
    return backend


def _gpu(backend: str | None):
    """The device of ``backend`` (``core.gpu.get_gpu``); no adapter for a backend asked for is an ArgumentError
    naming it with the backends this machine offers."""
    from .core.gpu import get_gpu, offered_backends

    try:
        return get_gpu(backend)
    except NoAdapterError as error:
        offered = offered_backends() if backend is not None else []
        if not offered:
            raise ApiError(str(error)) from error
        raise ArgumentError("backend", backend, f"no GPU adapter found for it (this machine offers {', '.join(offered)})"
                            f"; give {{backend}} {offered[0]!r} or 'auto'") from None


def _size(size) -> tuple[int, int]:
    valid = (isinstance(size, (tuple, list)) and len(size) == 2
             and all(isinstance(s, (int, np.integer)) and not isinstance(s, bool) and 1 <= s <= 16384 for s in size))
    if not valid:
        raise ArgumentError("size", size, "expected (width, height), integers 1 to 16384")
    return int(size[0]), int(size[1])


_renderers: list = []  # (scene, gpu, Renderer), the most recently used last
_cache_lock = threading.RLock()  # the device and renderer caches, shared by the threads that render


def renderer_for(scene: Scene, gpu):
    """The cached Renderer of ``scene`` on ``gpu`` (an equal scene: the same renderer), made on first use; at most
    MAX_RENDERERS are kept."""
    from .relief.renderer import Renderer

    for i, (known, known_gpu, renderer) in enumerate(_renderers):
        if known_gpu is gpu and known == scene:
            _renderers.append(_renderers.pop(i))
            return renderer
    renderer = Renderer(scene, gpu)
    _renderers.append((scene, gpu, renderer))
    del _renderers[:-MAX_RENDERERS]
    return renderer


@dataclass(frozen=True)
class Prepared:
    """A render made ready (``prepare``): the scene's renderer with the maps the technique needs built, the draw
    configuration, the camera and the frame size."""

    renderer: Renderer
    draw: DrawConfig
    camera: Camera
    size: tuple[int, int]

    @_user_errors()
    def image(self, mode: str = "color", camera: Camera | None = None) -> OffscreenImage:
        """The frame drawn offscreen (``Renderer.render``; ``mode`` "albedo" draws the unlit albedo), from
        ``camera`` (None: the prepared one). A frame the adapter cannot allocate is a FrameError naming ``size``."""
        return self.renderer.render(self.draw, self.size, camera or self.camera, mode, size_name="size")


@dataclass(frozen=True)
class _Call:
    """A call's arguments, checked (``_checked``): what ``prepare`` and ``view`` build from."""

    scene: Scene
    camera: Camera
    technique: object  # the registry's Technique
    filtering: dict  # filter, derivatives (registry names) and shadows
    size: tuple[int, int]
    backend: str | None


def _checked(scene, technique, size, camera, material, height_scale, uv_scale, filter, derivatives, shadows,
             backend) -> _Call:
    """Every argument of ``render``/``prepare``/``view`` checked, before the GPU starts: an ArgumentError (or an
    InputError) naming the first bad one."""
    from .relief.filters import DEFAULT_DERIVATIVES, DEFAULT_FILTER, get_derivatives, get_filter
    from .techniques import Technique, get_technique

    size = _size(size)
    spec = CameraSpec.of(camera)
    if shadows is not None and shadows not in SHADOW_MODES:
        raise ArgumentError("shadows", shadows, f"expected one of {', '.join(SHADOW_MODES)}, or None")
    backend = _backend(backend)
    scene = scene_of(scene, material, height_scale, uv_scale)
    view = camera_for(scene, spec)
    technique = technique or scene.technique
    if not isinstance(technique, Technique):
        technique = _entry("technique", technique, get_technique)
    filtering = {"filter": _entry("filter", filter or DEFAULT_FILTER, get_filter).name,
                 "derivatives": _entry("derivatives", derivatives or DEFAULT_DERIVATIVES, get_derivatives).name,
                 "shadows": shadows}
    return _Call(scene, view, technique, filtering, size, backend)


@_user_errors()
def prepare(scene=None, technique=None, size: tuple[int, int] = DEFAULT_SIZE, camera=None, *, material=None,
            height_scale=None, uv_scale=None, filter: str | None = None, derivatives: str | None = None,
            shadows: str | None = None, backend: str | None = None, keep: bool = True) -> Prepared:
    """Everything ``render`` does before it draws (the arguments are ``render``'s; ``technique`` may also be a
    ``Technique``): every argument checked before the GPU starts, the renderer made (``keep``: the scene's kept
    renderer, ``renderer_for``; False: one of its own, dropped with the result), the maps the technique needs built
    (a progress bar on a terminal). ``wgpuviewer render`` and the viewer's offscreen fallback draw through it."""
    from .core.commands import terminal_progress
    from .relief.renderer import Renderer, check_frame_size

    call = _checked(scene, technique, size, camera, material, height_scale, uv_scale, filter, derivatives, shadows,
                    backend)
    with _cache_lock:  # one device per backend and one kept renderer per scene, also when threads ask at once
        gpu = _gpu(call.backend)
        check_frame_size(gpu, call.size, "size")
        renderer = renderer_for(call.scene, gpu) if keep else Renderer(call.scene, gpu)
    with terminal_progress(f"maps for {call.technique.name}") as progress:
        renderer.prepare(call.technique, progress)
    return Prepared(renderer, renderer.config(call.technique, **call.filtering), call.camera, call.size)


@_user_errors()
def render(scene=None, technique: str | None = None, size: tuple[int, int] = DEFAULT_SIZE, camera=None,
           mode: str = "color", *, alpha: bool = False, material=None, height_scale=None, uv_scale=None,
           filter: str | None = None, derivatives: str | None = None, shadows: str | None = None,
           backend: str | None = None) -> np.ndarray:
    """Render a scene offscreen and return the array ``wgpuviewer render -o OUT.npy`` writes.

    ``scene``: None (the built-in default scene), a scene .toml path or a ``Scene``; ``technique``: a registry
    name (``wgpuviewer techniques``; default: the scene's); ``size``: (width, height); ``camera``: None (the
    scene's), a dict or a ``CameraSpec`` (position, target, fov, view_angle); ``mode``: one of
    ``relief.output.OUTPUT_MODES`` (``color``: (H, W, 3) float32 sRGB in [0, 1]; the others: float32 data, NaN
    where nothing was drawn); ``alpha``: colour and albedo get a fourth channel, 1 where drawn and 0 on the
    background (``render --alpha``). ``material``: a material folder (a str or Path) shown on the scene's first
    plane; ``height_scale``, ``uv_scale``: the subject's relief depth and tiling; ``filter``, ``derivatives``: the
    texture filter and its derivative source (``wgpuviewer filters``); ``shadows``: "off", "hard" or "soft" for
    every material (``render --shadows``; None: each material's own ``shadows``); ``backend``: auto, vulkan, metal,
    dx12 or gl (None: ``$WGPUVIEWER_BACKEND``, else auto).

    Errors: a bad argument is an ``ArgumentError`` naming it; a problem in a file (the scene, a texture) an
    ``ApiError`` naming the file and key; both are ValueErrors, checked before the GPU starts where they can be.

    The maps a technique needs are built on first use (and cached on disk); the renderer of a scene is kept, so
    repeated renders of it (other techniques, cameras, modes) cost only the drawing. Safe from several threads:
    their frames are drawn one at a time on the device, each correct (the module's docstring says how).

    >>> import wgpuviewer
    >>> image = wgpuviewer.render(technique="pom", size=(320, 180), camera={"view_angle": 70})
    >>> image.shape
    (180, 320, 3)
    """
    from .relief.output import OUTPUT_MODES, mode_data

    size = _size(size)
    if mode not in OUTPUT_MODES:
        raise ArgumentError("mode", mode, f"expected one of {', '.join(OUTPUT_MODES)}")
    prepared = prepare(scene, technique, size, camera, material=material, height_scale=height_scale,
                       uv_scale=uv_scale, filter=filter, derivatives=derivatives, shadows=shadows, backend=backend)
    return mode_data(prepared.image(mode), mode, alpha)


@_user_errors()
def view(scene=None, technique: str | None = None, size: tuple[int, int] = DEFAULT_WIDGET_SIZE, camera=None, *,
         material=None, height_scale=None, uv_scale=None, filter: str | None = None, derivatives: str | None = None,
         shadows: str | None = None, backend: str | None = None):
    """The interactive viewer (keys, HUD, A/B split) as a Jupyter widget, through rendercanvas's Jupyter backend
    (``jupyter_rfb``): the cell that ends with it shows it, and it draws while a browser shows it. The arguments
    are ``render``'s, checked as ``render`` checks them (before the GPU starts, the same errors); ``size`` is the
    widget's in logical pixels; ``camera`` is where the viewer's cameras start (R resets to it). Returns the widget
    (``snapshot()`` gives its last frame as a picture)."""
    from .viewer.app import Viewer

    call = _checked(scene, technique, size, camera, material, height_scale, uv_scale, filter, derivatives, shadows,
                    backend)
    _gpu(call.backend)  # no adapter for the backend: an ArgumentError here, as render raises it
    scene = replace(call.scene, camera=call.camera)
    viewer = Viewer(scene, call.technique.name, call.backend, gui="jupyter", size=call.size, **call.filtering)
    viewer.window.request_draw(viewer.draw)  # the widget keeps the viewer alive through its draw function
    return viewer.window.canvas


__all__ = ["DEFAULT_SIZE", "ApiError", "ArgumentError", "CameraSpec", "Prepared", "camera_for", "prepare", "render",
           "scene_of", "subject", "view", "with_relief"]
