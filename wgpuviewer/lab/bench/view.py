"""Benchmark views: a full-screen relief plane seen at a given centre angle, each pixel's ray, the
float64 reference hits of those rays and a CPU shading model for the image error.

The set-up (also in docs/benchmarks.md):

- A plane (``type = "plane"``, u along local +X, v along local +Z, normal +Y) turned by ``AZIMUTH``
  degrees about its normal, so rays cross the texel grid diagonally rather than along a mortar line.
- The camera looks at the plane's centre from distance 1 at ``angle`` degrees from the normal,
  with a narrow vertical field of view (``FOV`` = 1.5 degrees): the view angle varies by about
  +-0.75 degrees over the frame (the exact range over the covered pixels is reported with each row).
  A wide lens could not fill the frame at grazing angles: the upper rows would look past the horizon.
- The plane is sized and placed to cover the whole frame, plus the longest parallax offset of any
  pixel, so no ray leaves the relief through the plane's border.
- The texture tiling (``uv_scale``) is chosen per view so that no pixel of the frame minifies the
  height map (at most ``MAX_FOOTPRINT`` texels per pixel): every depth fetch is a mip level 0 fetch,
  which is what the float64 reference models. The error measured is the search error of the
  technique, not mip filtering.
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer import camera as cam
from wgpuviewer import textures
from wgpuviewer.core.color import linear_to_srgb
from wgpuviewer.core.sampling import bilinear
from wgpuviewer.relief.reference import exact_hit, uv_error_texels
from wgpuviewer.scene import Camera, Scene, parse_scene

FOV = 1.5  # vertical field of view, degrees
AZIMUTH = 30.0  # plane rotation about its normal, degrees
HEIGHT_SCALE = 0.05  # relief depth in UV units (one texture tile = 1)
MAX_FOOTPRINT = 0.9  # texels per pixel at the most minified pixel of the frame
LIGHT_TRAVELS = (0.4, -1.0, -0.3)  # world direction the directional light travels along


@dataclass(frozen=True)
class HeightMap:
    """A benchmark height map: ``height`` (h, w) in [0, 1]; ``texture`` is the scene TOML value
    for both its height and its albedo (a builtin table or a file path)."""

    name: str
    height: np.ndarray
    texture: str
    source: str  # for the report

    @property
    def size(self) -> tuple[int, int]:
        return self.height.shape[1], self.height.shape[0]


SKIMAGE_MAPS = ("brick", "grass", "gravel")


def load_heightmap(name: str, builtin_size: int, workdir: Path, real_size: int = 0) -> HeightMap:
    """A builtin (textures.BUILTINS) at ``builtin_size``², or a scikit-image texture (8-bit grey,
    brighter = higher, also used as the albedo) written to ``workdir`` as PNG, area-downscaled to at most
    ``real_size`` texels per side when that is given (0: as bundled)."""
    if name in textures.BUILTINS:
        size = (builtin_size, builtin_size)
        texture = f'{{ builtin = "{name}", size = [{size[0]}, {size[1]}] }}'
        return HeightMap(name, textures.builtin_height(name, size), texture, f"builtin {name} {size[0]}x{size[1]}")
    if name in SKIMAGE_MAPS:
        import cv2
        import skimage.data

        grey = np.asarray(getattr(skimage.data, name)(), np.uint8)
        origin = f"skimage.data.{name}() {grey.shape[1]}x{grey.shape[0]} (scikit-image)"
        if real_size and max(grey.shape) > real_size:
            scale = real_size / max(grey.shape)
            size = (round(grey.shape[1] * scale), round(grey.shape[0] * scale))
            grey = cv2.resize(grey, size, interpolation=cv2.INTER_AREA)
            origin += f", downscaled to {size[0]}x{size[1]}"
        path = Path(workdir) / f"skimage_{name}_{grey.shape[1]}x{grey.shape[0]}.png"
        if not path.exists():
            cv2.imwrite(str(path), grey)
        height = grey.astype(np.float32) / 255.0
        return HeightMap(name, height, _toml_string(str(path)), origin)
    raise KeyError(name)


def _toml_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


@dataclass
class View:
    """One height map seen at one centre angle: the scene and every pixel's ray."""

    heightmap: HeightMap
    angle: float
    size: tuple[int, int]  # frame (W, H)
    scene: Scene
    uv0: np.ndarray  # (H, W, 2) float64 entry uv of each pixel centre's ray
    v_ts: np.ndarray  # (H, W, 3) float64 unit tangent-space view vector
    angle_min: float  # view angle range over the frame, degrees
    angle_max: float
    light_ts: np.ndarray  # (3,) unit tangent-space direction towards the light


def _rotation_y(degrees: float) -> np.ndarray:
    return cam.rotation_xyz((0.0, degrees, 0.0))[:3, :3]


def _pixel_rays(camera: Camera, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """World-space eye and unit directions (H, W, 3) through each pixel centre."""
    w, h = size
    inv = np.linalg.inv(cam.perspective(camera.fov, w / h, camera.near, camera.far)
                        @ cam.look_at(camera.position, camera.target, camera.up))
    j, i = np.mgrid[0:h, 0:w]
    ndc = np.stack([(i + 0.5) / w * 2 - 1, 1 - (j + 0.5) / h * 2, np.ones((h, w)), np.ones((h, w))], -1)
    far = ndc @ inv.T
    far = far[..., :3] / far[..., 3:]
    eye = np.asarray(camera.position, np.float64)
    d = far - eye
    return eye, d / np.linalg.norm(d, axis=-1, keepdims=True)


def make_view(heightmap: HeightMap, angle: float, size: tuple[int, int]) -> View:
    """The scene and rays for ``heightmap`` seen at ``angle`` degrees (centre of the frame)."""
    if not 0.0 <= angle < 90.0:
        raise ValueError(f"angle {angle}: expected 0 <= angle < 90")
    theta = np.radians(angle)
    eye = np.array([0.0, np.cos(theta), np.sin(theta)])
    camera = Camera(tuple(eye), (0.0, 0.0, 0.0), (0.0, 0.0, -1.0), FOV, 1e-3, 1e3)
    eye, dirs = _pixel_rays(camera, size)
    if not (dirs[..., 1] < -1e-9).all():
        raise ValueError(f"angle {angle}: some pixels look past the horizon; use a smaller angle")
    s = -eye[1] / dirs[..., 1]
    world = eye + dirs * s[..., None]
    rot = _rotation_y(AZIMUTH)
    local = world @ rot  # world -> plane-local: R^T p, row vectors
    to_eye = -dirs @ rot
    v_ts = np.stack([to_eye[..., 0], to_eye[..., 2], to_eye[..., 1]], -1)  # T = +X, B = +Z, N = +Y
    angles = np.degrees(np.arccos(np.clip(v_ts[..., 2], -1, 1)))

    # Texel footprint per world unit of the plane: a pixel's largest step in local plane units.
    dx = np.hypot(*np.diff(local[..., [0, 2]], axis=1).transpose(2, 0, 1))
    dy = np.hypot(*np.diff(local[..., [0, 2]], axis=0).transpose(2, 0, 1))
    world_per_pixel = max(float(dx.max()) if dx.size else 0.0, float(dy.max()) if dy.size else 0.0)
    if world_per_pixel == 0.0:  # a 1x1 frame: one texel per pixel's width at the centre
        world_per_pixel = float(s.max()) * 2 * np.tan(np.radians(FOV) / 2) / max(size[1], 1) / np.cos(theta)
    texels = max(heightmap.size)
    uv_per_world = MAX_FOOTPRINT / (world_per_pixel * texels)  # one tile spans 1 / uv_per_world

    # Plane rectangle (local): the frame's footprint grown by the longest parallax offset.
    span = HEIGHT_SCALE * float(np.max(np.hypot(v_ts[..., 0], v_ts[..., 1]) / v_ts[..., 2])) / uv_per_world
    margin = span * 1.1 + world_per_pixel * 4
    lo = local[..., [0, 2]].reshape(-1, 2).min(0) - margin
    hi = local[..., [0, 2]].reshape(-1, 2).max(0) + margin
    # Shift the texture so the frame centre sees the middle of a tile, where the hard cases put
    # their feature (spike, wall, step): grow the plane's low side by the fractional shift.
    centre_uv = (_frame_centre(local) - lo) * uv_per_world
    lo = lo - np.mod(0.5 - centre_uv, 1.0) / uv_per_world
    extent = hi - lo
    centre = (lo + hi) / 2
    uv_scale = extent * uv_per_world
    position = rot @ np.array([centre[0], 0.0, centre[1]])
    uv0 = (local[..., [0, 2]] - lo) * uv_per_world

    l_world = -np.asarray(LIGHT_TRAVELS, np.float64)
    l_local = rot.T @ (l_world / np.linalg.norm(l_world))
    light_ts = np.array([l_local[0], l_local[2], l_local[1]])

    distances = np.linalg.norm(world - eye, axis=-1)
    near, far = float(distances.min()) * 0.5, float(distances.max()) * 2.0 + 1.0
    text = SCENE_TEMPLATE.format(
        eye=_vec(eye), fov=FOV, near=near, far=far, light=_vec(LIGHT_TRAVELS), texture=heightmap.texture,
        height_scale=HEIGHT_SCALE, uv_scale=_vec(uv_scale), size=_vec(extent), position=_vec(position),
        azimuth=AZIMUTH, name=f"bench-{heightmap.name}-{angle:g}",
    )
    scene = parse_scene(text)
    return View(heightmap, float(angle), tuple(size), scene, uv0, v_ts,
                float(angles.min()), float(angles.max()), light_ts)


def _frame_centre(local: np.ndarray) -> np.ndarray:
    """Plane-local (x, z) where the ray through the frame centre meets the plane."""
    h, w = local.shape[:2]
    rows = [h // 2 - 1, h // 2] if h % 2 == 0 else [h // 2]
    cols = [w // 2 - 1, w // 2] if w % 2 == 0 else [w // 2]
    return local[np.ix_(rows, cols)][..., [0, 2]].reshape(-1, 2).mean(0)


def _vec(v) -> str:
    return "[" + ", ".join(repr(float(x)) for x in v) + "]"


SCENE_TEMPLATE = """
[scene]
name = "{name}"
[camera]
position = {eye}
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov = {fov!r}
near = {near!r}
far = {far!r}
[[lights]]
type = "directional"
direction = {light}
[materials.relief]
albedo = {texture}
height = {texture}
height_scale = {height_scale!r}
uv_scale = {uv_scale}
[[objects]]
type = "plane"
material = "relief"
size = {size}
position = {position}
rotation = [0.0, {azimuth!r}, 0.0]
"""


def eval_grid(size: tuple[int, int], max_pixels: int) -> tuple[np.ndarray, np.ndarray]:
    """Row and column indices of a regular pixel subsample of at most ``max_pixels`` pixels."""
    w, h = size
    stride = max(1, int(np.ceil(np.sqrt(w * h / max(max_pixels, 1)))))
    rows = np.arange(stride // 2, h, stride)
    cols = np.arange(stride // 2, w, stride)
    return np.meshgrid(rows, cols, indexing="ij")


@dataclass
class Reference:
    """Float64 exact hits of the evaluated pixels' rays, and the image shaded at them."""

    rows: np.ndarray  # (N,) pixel rows
    cols: np.ndarray
    uv: np.ndarray  # (N, 2)
    valid: np.ndarray  # (N,)
    color: np.ndarray  # (N, 3) sRGB in [0, 1], shaded at the reference uv


def reference(view: View, max_pixels: int, hit=None) -> Reference:
    """The float64 exact hits of the evaluated pixels (``hit``: already computed by ``exact_hit`` on
    ``reference_rays``) and the image shaded at them."""
    rows, cols = (a.ravel() for a in eval_grid(view.size, max_pixels))
    if hit is None:
        hit = exact_hit(*reference_rays(view, max_pixels))
    shader = Shader(view)
    color = np.full((len(rows), 3), np.nan)
    color[hit.valid] = shader(hit.uv[hit.valid])
    return Reference(rows, cols, hit.uv, hit.valid, color)


def reference_rays(view: View, max_pixels: int) -> tuple:
    """``exact_hit``'s arguments for the evaluated pixels: depth exactly as the GPU depth texture holds it, entry
    uv, view vectors, height scale."""
    rows, cols = (a.ravel() for a in eval_grid(view.size, max_pixels))
    depth = textures.load_depth(view.scene.materials["relief"].height)
    return depth, view.uv0[rows, cols], view.v_ts[rows, cols], HEIGHT_SCALE


class _Later:
    """A reference computed when first asked for (no pool)."""

    def __init__(self, view: View, max_pixels: int):
        self.view, self.max_pixels = view, max_pixels

    def result(self) -> Reference:
        return reference(self.view, self.max_pixels)


class _Pooled:
    def __init__(self, view: View, max_pixels: int, future):
        self.view, self.max_pixels, self.future = view, max_pixels, future

    def result(self) -> Reference:
        return reference(self.view, self.max_pixels, self.future.result())


def reference_pool(views: list[View], max_pixels: int, workers: int) -> list:
    """One pending reference per view, in order (``.result()`` gives the Reference). ``workers`` > 0: the exact hits
    are computed in that many processes (spawned: the GPU device is not forked), all submitted now; -1: one per
    CPU core but one, at most 8; 0: each in this process when asked for."""
    if workers < 0:
        workers = min(8, max(1, (os.cpu_count() or 2) - 1))
    if workers == 0 or not views:
        return [_Later(v, max_pixels) for v in views]
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
    pending = [_Pooled(v, max_pixels, pool.submit(exact_hit, *reference_rays(v, max_pixels))) for v in views]
    pool.shutdown(wait=False)  # the workers finish the submitted work, then exit
    return pending


class Shader:
    """CPU shading at given hit UVs: the renderer's model without the specular term.

    colour = albedo(uv) * (0.2 + max(dot(L, n(uv)), 0)), sRGB-encoded; albedo and the normal map
    are the textures the renderer uploads (linear albedo; normals derived from the height map as
    the renderer derives them), sampled bilinearly with repeat addressing at mip level 0.
    """

    def __init__(self, view: View):
        from maptools.cache import cached_generate

        material = view.scene.materials["relief"]
        self.albedo = np.asarray(textures.load_albedo(material.albedo), np.float64)
        height = 1.0 - np.asarray(textures.load_depth(material.height), np.float32)
        normal = cached_generate("normal", height, backend="cpu",
                                 strength=material.height_scale * height.shape[1], y="directx")
        self.normal = np.asarray(normal, np.float64)
        self.light = view.light_ts

    def __call__(self, uv: np.ndarray) -> np.ndarray:
        albedo = bilinear(self.albedo, uv)
        n = bilinear(self.normal, uv)
        n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-12)
        linear = albedo * (0.2 + np.maximum(n @ self.light, 0.0))[:, None]
        return linear_to_srgb(np.clip(linear, 0.0, 1.0))


PSNR_CAP = 99.0  # dB; identical images (MSE 0) are reported as this


@dataclass
class Errors:
    uv_texels: np.ndarray  # per evaluated, covered, uncapped pixel with a valid reference
    psnr: float
    pixels: int


def errors(view: View, ref: Reference, data: np.ndarray, covered: np.ndarray, shader: Shader) -> Errors:
    """UV error (texels) and PSNR of one render's raw trace ``data`` against the reference."""
    d = data[ref.rows, ref.cols]
    ok = covered[ref.rows, ref.cols] & ref.valid & (d[:, 3] >= 0) & np.isfinite(d[:, :2]).all(1)
    uv = d[ok, :2].astype(np.float64)
    err = uv_error_texels(uv, ref.uv[ok], view.heightmap.size)
    if ok.any():
        mse = float(np.mean((shader(uv) - ref.color[ok]) ** 2))
        psnr = PSNR_CAP if mse <= 10 ** (-PSNR_CAP / 10) else float(-10 * np.log10(mse))
    else:
        psnr = float("nan")
    return Errors(err, psnr, int(ok.sum()))
