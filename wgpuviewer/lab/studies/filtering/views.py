"""The study's scenes: a relief plane with a high-frequency albedo, seen at a view angle with a chosen
minification, and the float64 geometry of any (sub-)pixel's view ray.

Set-up (also in docs/filtering.md): a plane (u along +X, v along +Z, normal +Y) turned ``AZIMUTH`` degrees about
its normal, the camera at distance 1 from its centre, ``angle`` degrees from the normal. The vertical field of
view shrinks at grazing angles so that the top of the frame stays ``HORIZON_MARGIN`` degrees below the horizon
(``fov = min(FOV, 2 (90 - HORIZON_MARGIN - angle))``): every pixel sees the plane, none sees infinitely many
texels. The tiling (``uv_scale``) makes the frame centre's footprint ``footprint`` texels per pixel across the
view (``footprint / cos(angle)`` along it). Albedo and relief are separate textures of the same size, so the
relief's occlusion and the albedo's frequencies are independent. Rays are traced with the exact ``maxmip``
technique, so the filters are compared on the true hits.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wgpuviewer import camera as cam
from wgpuviewer import textures
from wgpuviewer.core.errors import UserError
from wgpuviewer.scene import Camera, Scene, parse_scene

FOV = 30.0  # vertical field of view (degrees) away from grazing angles
HORIZON_MARGIN = 2.0  # degrees between the top of the frame and the horizon
AZIMUTH = 30.0  # plane rotation about its normal: the view crosses the texel grid diagonally
HEIGHT_SCALE = 0.05  # relief depth in UV units of one tile
TEXTURE_SIZE = 256  # albedo and relief, texels per side
TECHNIQUE = "maxmip"  # exact first hits (to float32) for the filters and the reference alike

#: Reliefs: builtin height maps; flat0 is a flat relief (every ray reaches the floor, nothing is hidden).
RELIEFS = {"bricks": "bricks (occlusion at the mortar)", "step": "one 0-to-1 step per tile (occlusion behind it)",
           "wall": "a one-texel wall per tile", "flat0": "flat (depth 1: displaced, nothing hidden)",
           "bumps": "smooth bumps (occlusion behind their crests at grazing views; the tuning cases' relief)",
           "brick": "scikit-image's brick photograph, 256x256 (brighter = higher; its own albedo is the photograph)"}
OCCLUDING = ("bricks", "step", "wall", "bumps", "brick")
#: Photographic reliefs: scikit-image's bundled grey textures, area-downscaled to TEXTURE_SIZE (a PNG per relief,
#: written into the study's folder; the height and the "own" albedo alike).
PHOTO_RELIEFS = ("brick",)
#: High-frequency albedos (sRGB PNGs written into the study's folder).
#: "own": the relief builtin's own albedo, whose colour follows the height (mortar vs brick, low vs high side of a
#: step): there the hidden texels differ from the visible ones, the case the filtering paper is about.
ALBEDOS = {"checker": "2-texel checker (period 4 texels)", "stripes": "stripes, period 3 texels, 20 degrees off u",
           "photo": "scikit-image astronaut photograph, 256x256", "own": "the relief builtin's own albedo",
           "masked": "a 1-texel checker on the relief's low parts (height below 1/2: the mortar, the low side of a "
                     "step), a flat brick red on the high parts"}
#: Albedos made from the relief's height (a file per relief).
RELIEF_ALBEDOS = ("masked",)
MASK_LEVEL = 0.5  # "masked": height below this is a low part


@dataclass(frozen=True)
class Case:
    relief: str
    albedo: str
    angle: float  # degrees from the normal at the frame centre
    footprint: float  # texels per pixel across the view at the frame centre

    @property
    def name(self) -> str:
        return f"{self.relief}-{self.albedo}-{self.angle:g}deg-x{self.footprint:g}"

    @property
    def occluding(self) -> bool:
        return self.relief in OCCLUDING


def albedo_image(name: str, size: int = TEXTURE_SIZE, relief: str = "") -> np.ndarray:
    """(size, size, 3) sRGB-encoded albedo in [0, 1] (what the PNG holds); ``relief`` for the RELIEF_ALBEDOS."""
    j, i = np.indices((size, size))
    if name == "masked":
        # High frequencies exactly where the relief hides texels at grazing views: the hidden texels differ from
        # the visible ones in detail as well as in colour, unlike "own" (smooth) and the relief-blind albedos.
        low = relief_height(relief, size) < MASK_LEVEL
        fine = np.where((i + j) % 2, 0.9, 0.08)[..., None] * np.array([1.0, 0.95, 0.85])
        return np.where(low[..., None], fine, np.array([0.62, 0.25, 0.18]))
    if name == "checker":
        grey = np.where((i // 2 + j // 2) % 2, 0.85, 0.15)
        return np.repeat(grey[..., None], 3, axis=2)
    if name == "stripes":
        t = np.radians(20.0)
        phase = (i * np.cos(t) + j * np.sin(t)) / 3.0 * size / round(size / 3.0)  # an integer count per tile
        grey = 0.5 + 0.4 * np.sign(np.sin(2 * np.pi * phase))
        colour = np.stack([grey, 0.6 * grey + 0.2, 1.0 - 0.8 * grey], -1)
        return np.clip(colour, 0.0, 1.0)
    if name == "photo":
        import cv2
        import skimage.data

        image = np.asarray(skimage.data.astronaut(), np.float32) / 255.0
        return np.clip(cv2.resize(image, (size, size), interpolation=cv2.INTER_AREA), 0.0, 1.0)
    raise UserError(f"albedo {name!r}: unknown; expected one of {', '.join(ALBEDOS)}")


def relief_height(name: str, size: int = TEXTURE_SIZE) -> np.ndarray:
    """(size, size) float32 height in [0, 1] of a builtin relief or a photographic one (brighter = higher)."""
    if name not in PHOTO_RELIEFS:
        return textures.builtin_height(name, (size, size))
    import cv2
    import skimage.data

    grey = cv2.resize(np.asarray(getattr(skimage.data, name)(), np.uint8), (size, size), interpolation=cv2.INTER_AREA)
    return grey.astype(np.float32) / 255.0  # the 8-bit values the PNG holds


def write_relief(name: str, folder: Path) -> str:
    """The scene TOML value of the relief's height (and "own" albedo): a builtin table, or the photographic relief
    written once as an 8-bit grey PNG in ``folder``."""
    if name not in PHOTO_RELIEFS:
        return f'{{ builtin = "{name}", size = [{TEXTURE_SIZE}, {TEXTURE_SIZE}] }}'
    import cv2

    path = Path(folder) / f"relief_{name}.png"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        if not cv2.imwrite(str(path), np.rint(relief_height(name) * 255).astype(np.uint8)):
            raise UserError(f"{path}: could not write the relief texture")
    return _toml_path(path)


def write_albedo(name: str, folder: Path, relief: str = "") -> Path:
    """The albedo as an 8-bit sRGB PNG in ``folder`` (written once; one per relief for the RELIEF_ALBEDOS)."""
    import cv2

    path = Path(folder) / (f"albedo_{name}_{relief}.png" if name in RELIEF_ALBEDOS else f"albedo_{name}.png")
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        rgb = np.rint(albedo_image(name, relief=relief) * 255).astype(np.uint8)
        if not cv2.imwrite(str(path), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)):
            raise UserError(f"{path}: could not write the albedo texture")
    return path


@dataclass
class View:
    case: Case
    size: tuple[int, int]  # frame (W, H)
    scene: Scene
    camera: Camera
    plane_size: tuple[float, float]
    uv_scale: tuple[float, float]
    rotation: np.ndarray  # (3, 3) plane-local -> world

    def rays(self, sub: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """World-space eye (3,) and unit directions (H * sub, W * sub, 3) through the centres of a sub x sub grid
        of sub-pixels in every pixel (the supersampled frame's pixel centres)."""
        w, h = self.size[0] * sub, self.size[1] * sub
        c = self.camera
        inverse = np.linalg.inv(cam.perspective(c.fov, w / h, c.near, c.far) @ cam.look_at(c.position, c.target, c.up))
        x = (np.arange(w) + 0.5) / w * 2.0 - 1.0
        y = 1.0 - (np.arange(h) + 0.5) / h * 2.0
        ndc = np.stack(np.broadcast_arrays(x[None, :], y[:, None], 1.0, 1.0), -1)
        far = ndc @ inverse.T
        eye = np.asarray(c.position, np.float64)
        d = far[..., :3] / far[..., 3:] - eye
        return eye, d / np.linalg.norm(d, axis=-1, keepdims=True)

    def entries(self, sub: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Float64 entry uv (H', W', 2) on the surface plane and tangent-space view vectors (H', W', 3) of the
        sub-pixel rays (the renderer's convention: V towards the eye, tangent = u, bitangent = v)."""
        eye, d = self.rays(sub)
        s = -eye[1] / d[..., 1]
        local = (eye + d * s[..., None]) @ self.rotation  # world -> plane-local (row vectors)
        w, depth = self.plane_size
        uv = np.stack([(local[..., 0] + w / 2) / w * self.uv_scale[0], (local[..., 2] + depth / 2) / depth
                       * self.uv_scale[1]], -1)
        to_eye = -d @ self.rotation
        return uv, np.stack([to_eye[..., 0], to_eye[..., 2], to_eye[..., 1]], -1)

    def shifted(self, texels: float) -> View:
        """The same view with the camera (and its target) moved ``texels`` texels along the frame's x axis, parallel
        to the plane: the picture slides over the relief by that much (the flicker sweep's frames)."""
        step = texels / (TEXTURE_SIZE * self.uv_scale[0] / self.plane_size[0])  # world units
        move = np.array([step, 0.0, 0.0])  # world X lies in the plane and along the frame's x at every angle
        c = self.camera
        camera = dataclasses.replace(c, position=tuple(float(x) for x in np.asarray(c.position) + move),
                                     target=tuple(float(x) for x in np.asarray(c.target) + move))
        return dataclasses.replace(self, camera=camera)


def make_view(case: Case, size: tuple[int, int], folder: Path) -> View:
    if not 0.0 <= case.angle <= 90.0 - 2 * HORIZON_MARGIN:
        raise UserError(f"angle {case.angle:g}: expected 0 to {90 - 2 * HORIZON_MARGIN:g} degrees")
    if case.relief not in RELIEFS:
        raise UserError(f"relief {case.relief!r}: unknown; expected one of {', '.join(RELIEFS)}")
    if case.albedo not in ALBEDOS:
        raise UserError(f"albedo {case.albedo!r}: unknown; expected one of {', '.join(ALBEDOS)}")
    if not case.footprint > 0:
        raise UserError(f"footprint {case.footprint!r}: expected texels per pixel > 0")
    theta = np.radians(case.angle)
    fov = float(min(FOV, 2.0 * (90.0 - HORIZON_MARGIN - case.angle)))
    eye = np.array([0.0, np.cos(theta), np.sin(theta)])
    camera = Camera(tuple(eye), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0) if case.angle > 0 else (0.0, 0.0, -1.0), fov,
                    0.01, 100.0)
    rotation = cam.rotation_xyz((0.0, AZIMUTH, 0.0))[:3, :3]
    view = View(case, tuple(size), None, camera, (1.0, 1.0), (1.0, 1.0), rotation)
    # Plane units per pixel across the view at the centre: distance 1, pixel angle fov / H.
    world_per_pixel = 2.0 * np.tan(np.radians(fov) / 2.0) / size[1]
    uv_per_world = case.footprint / (world_per_pixel * TEXTURE_SIZE)
    eye_w, d = view.rays(1)
    corners = d[[0, 0, -1, -1], [0, -1, 0, -1]]
    hits = eye_w + corners * (-eye_w[1] / corners[:, 1])[:, None]
    reach = np.abs(hits @ rotation)[:, [0, 2]].max()
    tan = np.tan(np.radians(min(case.angle + fov / 2, 89.0)))
    extent = 2.0 * (reach + 2.0 * HEIGHT_SCALE * tan / uv_per_world) + 1.0  # parallax offsets stay on the plane
    extent = float(extent)
    uv_scale = float(extent * uv_per_world)
    view.plane_size, view.uv_scale = (extent, extent), (uv_scale, uv_scale)
    relief = write_relief(case.relief, folder)
    albedo = relief if case.albedo == "own" else _toml_path(write_albedo(case.albedo, folder, case.relief))
    text = SCENE.format(name=case.name, eye=_vec(eye), up=_vec(camera.up), fov=fov, albedo=albedo,
                        relief=relief, scale=HEIGHT_SCALE, uv_scale=uv_scale, size=extent,
                        azimuth=AZIMUTH, technique=TECHNIQUE)
    view.scene = parse_scene(text)
    return view


def albedo_linear(view: View) -> np.ndarray:
    """The linear albedo (H, W, 3) float32 the renderer uploads for the view's material."""
    return textures.load_albedo(view.scene.materials["relief"].albedo)


def depth_map(view: View) -> np.ndarray:
    """The relief's depth (H, W) float32, as the GPU samples it."""
    return textures.load_depth(view.scene.materials["relief"].height)


def _vec(v) -> str:
    return "[" + ", ".join(repr(float(x)) for x in v) + "]"


def _toml_path(path: Path) -> str:
    return '"' + str(Path(path).resolve()).replace("\\", "\\\\").replace('"', '\\"') + '"'


SCENE = """
[scene]
name = "{name}"
techniques = ["{technique}"]
background = [0.0, 0.0, 0.0]
[camera]
position = {eye}
target = [0.0, 0.0, 0.0]
up = {up}
fov = {fov!r}
near = 0.01
far = 100.0
[materials.relief]
albedo = {albedo}
height = {relief}
height_scale = {scale!r}
uv_scale = [{uv_scale!r}, {uv_scale!r}]
[[objects]]
type = "plane"
material = "relief"
size = [{size!r}, {size!r}]
rotation = [0.0, {azimuth!r}, 0.0]
"""
