"""The Python API: ``render`` (a scene drawn offscreen into a numpy array), ``view`` (the interactive viewer as a
Jupyter widget), and what they share with ``wgpuviewer render``: the camera a render uses (``camera_for``, from a
``CameraSpec``) and a material's relief settings (``with_relief``).

Arguments are checked before the GPU starts; a bad one is an ``InputError`` (a ValueError) of one line naming it
(a bad scene file: a ``UserError`` naming the file and key, as in the CLI). The first GPU use is as quiet as the
CLI's: no driver line about ``XDG_RUNTIME_DIR`` (``core.gpu``); a software adapter is named once on stderr.

The subject of a scene: its first plane (where ``--material`` shows a folder), or its first object when it has
no plane. ``view_angle``, ``height_scale`` and ``uv_scale`` are about the subject.

Imports: ``core``, the scene modules, ``relief`` and (for ``view``) ``viewer``; never the measuring rooms. The CLI
imports it (``render``'s options); ``wgpuviewer/__init__`` exports its public names, loading it on first use.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from pathlib import Path

import numpy as np

from . import camera as cam
from .core.errors import InputError
from .scene import (
    SHADOW_MODES,
    Camera,
    Scene,
    _show,
    default_scene_path,
    load_scene,
    uv_scale_problem,
    with_folder_material,
)

#: The default frame size of ``render``: the CLI's (``cli.DEFAULT_SIZE``; a test holds them equal, the CLI cannot
#: import this module before its process is prepared).
DEFAULT_SIZE = (1280, 720)
#: ``view``'s default widget size in logical pixels: a notebook cell's width.
DEFAULT_WIDGET_SIZE = (640, 360)
#: Renderers ``render`` keeps: repeated renders of a scene reuse its textures, maps and pipelines; beyond this many
#: the least recently used one is dropped (its GPU memory released).
MAX_RENDERERS = 4

#: How messages name each setting: the API's argument names here; the CLI passes its option names.
API_NAMES = {"position": "camera.position", "target": "camera.target", "fov": "camera.fov",
             "view_angle": "camera.view_angle", "height_scale": "height_scale", "uv_scale": "uv_scale"}

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


def _label(names: dict, key: str, value) -> str:
    """``--camera 0,1,2`` for an option of the CLI, ``camera.position = (0, 1, 2)`` for an API argument."""
    name = names[key]
    if not name.startswith("--"):
        return f"{name} = {_show(value)}"
    if isinstance(value, (tuple, list, np.ndarray)):
        try:
            return f"{name} {','.join(f'{float(x):g}' for x in value)}"
        except (TypeError, ValueError):
            pass
    return f"{name} {value:g}" if isinstance(value, float) else f"{name} {value}"


def _number(names: dict, key: str, value, lo: float, hi: float, lo_open: bool, hi_open: bool) -> float:
    """A real number within lo..hi (open ends as given; hi may be inf): an InputError naming the setting otherwise."""
    if math.isinf(hi):
        expected = f"a number above {lo:g}" if lo_open else f"a number of at least {lo:g}"
    else:
        expected = f"a number from {lo:g}{' (exclusive)' if lo_open else ''} to {hi:g}{' (exclusive)' if hi_open else ''}"
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(f"{_label(names, key, value)}: expected {expected}")
    x = float(value)
    inside = (x > lo if lo_open else x >= lo) and (x < hi if hi_open else x <= hi)
    if not (math.isfinite(x) and inside):
        raise InputError(f"{_label(names, key, value)}: out of range, expected {expected}")
    return x


def _point(names: dict, key: str, value) -> np.ndarray:
    """Three finite numbers as a float64 vector: an InputError naming the setting otherwise."""
    try:
        p = np.asarray(value, np.float64)
    except (TypeError, ValueError):
        p = None
    if p is None or p.shape != (3,) or isinstance(value, (str, bytes)):
        raise InputError(f"{_label(names, key, value)}: expected a point of 3 numbers x, y, z")
    if not np.isfinite(p).all():
        raise InputError(f"{_label(names, key, value)}: expected finite numbers")
    return p


def subject(scene: Scene) -> int:
    """Index of the scene's subject: its first plane (where ``--material`` shows a folder), else its first object."""
    return next((i for i, o in enumerate(scene.objects) if o.kind == "plane"), 0)


def surface_normal(scene: Scene) -> np.ndarray:
    """The world-space unit normal of the subject's surface (``SURFACE_NORMALS``, rotated with its object)."""
    obj = scene.objects[subject(scene)]
    return cam.normalize(cam.rotation_xyz(obj.rotation)[:3, :3] @ np.asarray(SURFACE_NORMALS[obj.kind]))


def _perpendicular(v: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """``v`` without its component along the unit vector ``axis``."""
    return v - np.dot(v, axis) * axis


def camera_for(scene: Scene, spec: CameraSpec | dict | None = None, names: dict = API_NAMES) -> Camera:
    """The camera of a render: the scene's, changed by ``spec`` (see ``CameraSpec``), every value checked. The
    one way ``render``, ``view`` and ``wgpuviewer render --camera/--target/--fov/--view-angle`` build it; messages
    name the settings by ``names`` (the CLI's options, or the API's argument names)."""
    spec = CameraSpec.of(spec)
    base = scene.camera
    if spec.position is not None and spec.view_angle is not None:
        raise InputError(f"{_label(names, 'view_angle', spec.view_angle)}: {names['position']} places the camera "
                         f"too; give one of {names['position']} and {names['view_angle']}")
    target = _point(names, "target", spec.target) if spec.target is not None else np.asarray(base.target)
    fov = _number(names, "fov", spec.fov, 1, 179, True, True) if spec.fov is not None else base.fov
    if spec.view_angle is not None:
        angle = math.radians(_number(names, "view_angle", spec.view_angle, 0, 90, False, True))
        kind = scene.objects[subject(scene)].kind
        if kind not in SURFACE_NORMALS:  # a curved or mesh subject has no one normal to measure the angle from
            raise InputError(f"{_label(names, 'view_angle', spec.view_angle)}: the scene's subject (its first "
                             f"plane, else its first object) is a {kind}, which has no single surface normal; "
                             f"expected a subject of type {', '.join(SURFACE_NORMALS)}, or give {names['position']}")
        normal = surface_normal(scene)
        seen_from = np.asarray(base.position) - target
        distance = float(np.linalg.norm(seen_from))
        side = _perpendicular(seen_from, normal)  # the scene camera's side of the surface, along it
        if np.linalg.norm(side) < 1e-9 * max(distance, 1e-30):  # the scene camera is on the normal: its up
            side = _perpendicular(np.asarray(base.up), normal)
        position = target + distance * (math.cos(angle) * normal + math.sin(angle) * cam.normalize(side))
        key = "view_angle"
    elif spec.position is not None:
        position, key = _point(names, "position", spec.position), "position"
    else:
        position, key = np.asarray(base.position), "target" if spec.target is not None else None
    view = target - position
    distance = float(np.linalg.norm(view))
    if key is not None:  # the scene checked its own camera
        if distance < 1e-9:
            raise InputError(f"{_label(names, key, getattr(spec, key))}: the camera is at its target; expected "
                             f"{names['position']} and {names['target']} apart")
        if distance >= base.far:
            raise InputError(f"{_label(names, key, getattr(spec, key))}: the target is {distance:.4g} from the "
                             f"camera, beyond its far plane at {base.far:g} (the scene's camera.far); move them closer")
    forward = view / distance
    up = np.asarray(base.up)
    if np.linalg.norm(np.cross(up, forward)) < 1e-6:  # looking along up: the scene camera's view direction is up
        up = cam.normalize(_perpendicular(cam.normalize(np.subtract(base.target, base.position)), forward))
    return replace(base, position=tuple(float(x) for x in position), target=tuple(float(x) for x in target),
                   up=tuple(float(x) for x in up), fov=fov)


def with_relief(scene: Scene, height_scale=None, uv_scale=None, names: dict = API_NAMES) -> Scene:
    """``scene`` with the subject's material given a relief depth (``height_scale``, UV units, 0 to 1) and a
    tiling (``uv_scale``: one number for both directions, or (u, v), each above 0); None keeps the material's.
    Every object of that material shows the change. Checked as a scene's values are (the texel-coordinate limit
    included); messages name the settings by ``names``."""
    if height_scale is None and uv_scale is None:
        return scene
    name = scene.objects[subject(scene)].material
    material = scene.materials[name]
    if height_scale is not None:
        material = replace(material, height_scale=_number(names, "height_scale", height_scale, 0, 1, False, False))
    if uv_scale is not None:
        pair = (uv_scale, uv_scale) if np.ndim(uv_scale) == 0 else uv_scale
        if isinstance(pair, (str, bytes)) or np.ndim(pair) != 1 or len(pair) != 2:
            raise InputError(f"{_label(names, 'uv_scale', uv_scale)}: expected a number or two (u, v)")
        tiling = tuple(_number(names, "uv_scale", x, 0, math.inf, True, True) for x in pair)
        problem = uv_scale_problem(material, tiling)
        if problem:
            raise InputError(f"{_label(names, 'uv_scale', uv_scale)}: {problem}")
        material = replace(material, uv_scale=tiling)
    return replace(scene, materials={**scene.materials, name: material})


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
        scene = with_folder_material(scene, Path(material).expanduser())
    return with_relief(scene, height_scale, uv_scale)


def _size(size, name: str = "size") -> tuple[int, int]:
    valid = (isinstance(size, (tuple, list)) and len(size) == 2
             and all(isinstance(s, (int, np.integer)) and not isinstance(s, bool) and 1 <= s <= 16384 for s in size))
    if not valid:
        raise InputError(f"{name} = {_show(size)}: expected (width, height), integers 1 to 16384")
    return int(size[0]), int(size[1])


_renderers: list = []  # (scene, gpu, Renderer), the most recently used last


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
    background (``render --alpha``). ``material``: a material folder shown on the scene's first plane;
    ``height_scale``, ``uv_scale``: the subject's relief depth and tiling; ``filter``, ``derivatives``: the texture
    filter and its derivative source (``wgpuviewer filters``); ``shadows``: "off", "hard" or "soft" for every
    material (``render --shadows``; None: each material's own ``shadows``); ``backend``: auto, vulkan, metal, dx12
    or gl.

    The maps a technique needs are built on first use (and cached on disk); the renderer of a scene is kept, so
    repeated renders of it (other techniques, cameras, modes) cost only the drawing.

    >>> import wgpuviewer
    >>> image = wgpuviewer.render(technique="pom", size=(320, 180), camera={"view_angle": 70})
    >>> image.shape
    (180, 320, 3)
    """
    from .core.cli import terminal_progress
    from .core.gpu import get_gpu
    from .relief.filters import DEFAULT_DERIVATIVES, DEFAULT_FILTER, get_derivatives, get_filter
    from .relief.output import OUTPUT_MODES, mode_data
    from .relief.renderer import check_frame_size
    from .relief.techniques import get_technique

    size = _size(size)
    if mode not in OUTPUT_MODES:
        raise InputError(f"mode = {_show(mode)}: expected one of {', '.join(OUTPUT_MODES)}")
    spec = CameraSpec.of(camera)
    if shadows is not None and shadows not in SHADOW_MODES:
        raise InputError(f"shadows = {_show(shadows)}: expected one of {', '.join(SHADOW_MODES)}, or None")
    filtering = {"filter": get_filter(filter or DEFAULT_FILTER, "filter").name,
                 "derivatives": get_derivatives(derivatives or DEFAULT_DERIVATIVES, "derivatives").name,
                 "shadows": shadows}
    scene = scene_of(scene, material, height_scale, uv_scale)
    name = get_technique(technique or scene.technique, "technique").name
    view = camera_for(scene, spec)
    gpu = get_gpu(backend)
    check_frame_size(gpu, size, "size")
    renderer = renderer_for(scene, gpu)
    with terminal_progress(f"maps for {name}") as progress:
        renderer.prepare(name, progress)
    image = renderer.render(renderer.config(name, **filtering), size, view, mode=mode, size_name="size")
    return mode_data(image, mode, alpha)


def view(scene=None, technique: str | None = None, size: tuple[int, int] = DEFAULT_WIDGET_SIZE, camera=None, *,
         material=None, height_scale=None, uv_scale=None, filter: str | None = None, derivatives: str | None = None,
         shadows: str | None = None, backend: str | None = None):
    """The interactive viewer (keys, HUD, A/B split) as a Jupyter widget, through rendercanvas's Jupyter backend
    (``jupyter_rfb``): the cell that ends with it shows it, and it draws while a browser shows it. The arguments
    are ``render``'s; ``size`` is the widget's in logical pixels; ``camera`` is where the viewer's cameras start
    (R resets to it). Returns the widget (``snapshot()`` gives its last frame as a picture)."""
    from .relief.filters import DEFAULT_DERIVATIVES, DEFAULT_FILTER
    from .relief.techniques import get_technique
    from .viewer.app import Viewer

    size = _size(size)
    spec = CameraSpec.of(camera)
    scene = scene_of(scene, material, height_scale, uv_scale)
    name = get_technique(technique or scene.technique, "technique").name
    scene = replace(scene, camera=camera_for(scene, spec))
    viewer = Viewer(scene, name, backend, gui="jupyter", size=size, filter=filter or DEFAULT_FILTER,
                    derivatives=derivatives or DEFAULT_DERIVATIVES, shadows=shadows)
    viewer.window.request_draw(viewer.draw)  # the widget keeps the viewer alive through its draw function
    return viewer.window.canvas


__all__ = ["DEFAULT_SIZE", "CameraSpec", "camera_for", "render", "scene_of", "subject", "view", "with_relief"]
