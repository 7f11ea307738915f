"""The study's scene: a planar textured quad (``meshes.quad``) under a perspective camera (``camera.py``), seen along
rows of pixels (spans), and the nine coefficients of its screen-to-texture map.

Frame: ``span_length`` x ``rows`` pixels; span ``i`` is row ``y = i`` from ``x = 0``. The camera looks along -Z with
a horizontal field of view ``fov_x``; its vertical one follows from square pixels, so a frame of R rows is the middle
R rows of any taller frame of the same width. The quad is a wall leaning back by ``lean`` degrees and turned about
the vertical by the yaw that puts the angle between the view ray and the wall's normal at ``tilt`` degrees at the far
end of the middle row: 90 degrees is edge-on there (the denominator reaches 0), beyond 90 the span crosses the wall's
horizon (the denominator changes sign; those pixels see nothing).

Texture coordinates are in texels: ``texels_per_unit`` texels per world unit on the wall, tiles of
``texture_size`` texels (the renderer's ``uv_scale`` = tiles across the quad). ``offset`` moves the visible part of
the wall that many texels away from the texture origin (heavy tiling: the quad extends that far out of view), so
every method, the hardware rasteriser included, sees the same large coordinates.

The projective map from texel coordinates (u, v, 1) to homogeneous screen coordinates (x w, y w, w) is
``S @ VP @ M @ L``: L the quad's local position as an affine function of (u, v) (from the mesh's vertices), M the
object's model matrix, VP the camera's view-projection, S the viewport (pixel centres at integer x, y). Its inverse
gives ``(u', v', q') = K @ (x, y, 1)``, i.e. ``K = [[A1, B1, C1], [A2, B2, C2], [D, E, F]]``, ``u = u'/q'``,
``v = v'/q'``; q' = 1/w_clip > 0 in front of the eye. K is scaled by a power of two (exact) so that its largest
entry lies in [0.5, 1): the map is homogeneous, so this changes no result and keeps huge or tiny coefficient sets
away from float32 overflow and underflow.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from wgpuviewer import camera as cam
from wgpuviewer import meshes
from wgpuviewer.core.errors import InputError
from wgpuviewer.scene import Camera

#: |u| or |v| beyond this many texels has no fractional bits left in float32: such a pixel is flagged.
UMAX = 2.0**24
#: The longest span the kernels accept (their loops' hard cap).
MAX_SPAN = 16384
#: Texels of quad kept beyond the visible part of the frame on every side (the renderer's rasteriser needs a
#: covered frame; the offset counts from this margin).
MARGIN_TEXELS = 16.0


@dataclass(frozen=True)
class Setup:
    """What the study varies: span length (frame width), rows, tilt (far-end angle), coordinate offset (texels)."""

    span_length: int = 1920
    rows: int = 8
    tilt: float = 80.0
    offset: float = 0.0
    fov_x: float = 60.0
    lean: float = 10.0
    texels_per_unit: float = 1024.0
    texture_size: int = 256

    def __post_init__(self):
        if not (isinstance(self.span_length, int) and 1 <= self.span_length <= MAX_SPAN):
            raise InputError(f"span_length = {self.span_length!r}: expected an integer 1 to {MAX_SPAN}")
        if not (isinstance(self.rows, int) and 1 <= self.rows <= MAX_SPAN):
            raise InputError(f"rows = {self.rows!r}: expected an integer 1 to {MAX_SPAN}")
        if not (math.isfinite(self.lean) and 0.0 <= self.lean < 45.0):
            raise InputError(f"lean = {self.lean!r}: expected 0 to 45 degrees (exclusive)")
        if not (math.isfinite(self.tilt) and self.lean <= self.tilt <= 180.0 - self.lean):
            raise InputError(f"tilt = {self.tilt!r}: expected {self.lean:g} to {180 - self.lean:g} degrees")
        if not (math.isfinite(self.offset) and 0.0 <= self.offset <= 1e8):
            raise InputError(f"offset = {self.offset!r}: expected 0 to 1e8 texels")
        if not (math.isfinite(self.fov_x) and 1.0 <= self.fov_x <= 150.0):
            raise InputError(f"fov_x = {self.fov_x!r}: expected 1 to 150 degrees")
        if not (math.isfinite(self.texels_per_unit) and self.texels_per_unit > 0):
            raise InputError(f"texels_per_unit = {self.texels_per_unit!r}: expected a positive number")
        if not (isinstance(self.texture_size, int) and self.texture_size >= 1):
            raise InputError(f"texture_size = {self.texture_size!r}: expected a positive integer")


@dataclass(frozen=True)
class Spans:
    """Spans of equal length: span i covers pixels (x0[i] + n, y[i]), n = 0 .. length - 1."""

    x0: np.ndarray  # (R,) int64
    y: np.ndarray  # (R,) int64
    length: int

    def __post_init__(self):
        if not 1 <= self.length <= MAX_SPAN:
            raise InputError(f"span length {self.length}: expected 1 to {MAX_SPAN}")
        if self.x0.shape != self.y.shape or self.x0.ndim != 1 or self.x0.size == 0:
            raise InputError(f"spans: x0 {self.x0.shape} and y {self.y.shape} must be equal, non-empty 1D arrays")
        # Pixel coordinates reach the float32 kernels as exact integers.
        if np.abs(self.x0).max() + self.length > 2**24 or np.abs(self.y).max() > 2**24:
            raise InputError("spans: pixel coordinates beyond 2^24 are not exact in float32")

    @property
    def count(self) -> int:
        return int(self.x0.size)

    def pixels(self) -> tuple[np.ndarray, np.ndarray]:
        """(x, y) of every pixel, (R, L) float64."""
        n = np.arange(self.length)
        x = (self.x0[:, None] + n[None, :]).astype(np.float64)
        return x, np.broadcast_to(self.y[:, None].astype(np.float64), x.shape)


def rows_of(frame: tuple[int, int]) -> Spans:
    """The spans of a whole frame (W, H): one per row, from x = 0."""
    w, h = frame
    return Spans(np.zeros(h, np.int64), np.arange(h, dtype=np.int64), w)


def tiles_of(frame: tuple[int, int], width: int) -> Spans:
    """The spans of a whole frame (W, H) cut into pieces of ``width`` pixels (W a multiple of it), each its own span
    from its own start, as a tile or GPU rasteriser walks a row: row by row, left to right."""
    w, h = frame
    if not (isinstance(width, int) and 1 <= width <= w and w % width == 0):
        raise InputError(f"tile width {width!r}: expected a divisor of the frame width {w}")
    per_row = w // width
    return Spans(np.tile(np.arange(0, w, width, dtype=np.int64), h), np.repeat(np.arange(h, dtype=np.int64), per_row),
                 width)


@dataclass(frozen=True)
class Quad:
    """A built setup: the camera, the quad as a scene object, its coefficients and spans."""

    setup: Setup
    camera: Camera
    frame: tuple[int, int]  # (W, H) = (span_length, rows)
    yaw: float  # degrees about +Y
    size: tuple[float, float]  # quad width (u) and height (v), world units
    position: tuple[float, float, float]
    rotation: tuple[float, float, float]  # Euler XYZ degrees (scene convention)
    uv_scale: tuple[float, float]  # tiles across the quad
    coefficients: np.ndarray  # (3, 3) float64 K, normalised
    horizon: bool  # the frame sees past the wall's horizon (some q <= 0)

    @property
    def spans(self) -> Spans:
        return rows_of(self.frame)


def check_coefficients(coefficients) -> np.ndarray:
    """K as a (3, 3) float64 array, scaled by a power of two so its largest entry lies in [0.5, 1)."""
    k = np.asarray(coefficients, np.float64)
    if k.shape != (3, 3):
        raise InputError(f"coefficients: expected a 3x3 array [[A1, B1, C1], [A2, B2, C2], [D, E, F]], got {k.shape}")
    names = ("A1", "B1", "C1", "A2", "B2", "C2", "D", "E", "F")
    bad = ~np.isfinite(k.ravel())
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"coefficients: {names[i]} = {float(k.ravel()[i])}; expected finite numbers")
    peak = float(np.abs(k).max())
    if peak == 0.0 or not np.any(k[2]):
        raise InputError("coefficients: the denominator D x + E y + F is identically zero; expected a projective map")
    _, exponent = math.frexp(peak)
    return np.ldexp(k, -exponent)


def _camera(setup: Setup, far: float) -> Camera:
    w, h = setup.span_length, setup.rows
    fov_y = 2.0 * math.degrees(math.atan(math.tan(math.radians(setup.fov_x) / 2.0) * h / w))
    return Camera((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0), fov_y, 1e-3, far)


def _view_projection(camera: Camera, frame: tuple[int, int]) -> np.ndarray:
    w, h = frame
    return cam.perspective(camera.fov, w / h, camera.near, camera.far) @ cam.look_at(
        camera.position, camera.target, camera.up)


def _viewport(frame: tuple[int, int]) -> np.ndarray:
    """(clip x, clip y, clip w) -> (x w, y w, w), x and y pixel indices (centres at integers), rows down."""
    w, h = frame
    return np.array([[w / 2.0, 0.0, w / 2.0 - 0.5], [0.0, -h / 2.0, h / 2.0 - 0.5], [0.0, 0.0, 1.0]])


def _normal(lean: float, yaw: float) -> np.ndarray:
    return cam.rotation_xyz((lean, yaw, 0.0))[:3, :3] @ np.array([0.0, 0.0, 1.0])


def _pixel_direction(setup: Setup, x: float, y: float) -> np.ndarray:
    """Unit camera-space direction through pixel (x, y) (camera at the origin looking along -Z)."""
    w, h = setup.span_length, setup.rows
    half = math.tan(math.radians(setup.fov_x) / 2.0)
    d = np.array([((x + 0.5) / w * 2.0 - 1.0) * half, (1.0 - (y + 0.5) / h * 2.0) * half * h / w, -1.0])
    return d / np.linalg.norm(d)


def _solve_yaw(setup: Setup) -> float:
    """The yaw that puts the far end of the middle row at ``setup.tilt`` degrees from the wall's normal."""
    ray = _pixel_direction(setup, setup.span_length - 1, (setup.rows - 1) / 2.0)
    azimuth = math.degrees(math.atan2(ray[0], -ray[2]))

    def angle(yaw: float) -> float:
        return math.degrees(math.acos(float(np.clip(-ray @ _normal(setup.lean, yaw), -1.0, 1.0))))

    # Over [-azimuth, 180 - azimuth] the angle rises monotonically from about `lean` to about 180 - lean.
    lo, hi = -azimuth, 180.0 - azimuth
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if angle(mid) < setup.tilt else (lo, mid)
    return 0.5 * (lo + hi)


def build(setup: Setup) -> Quad:
    """The quad, camera and coefficients of ``setup``."""
    w, h = setup.span_length, setup.rows
    yaw = _solve_yaw(setup)
    rotation = cam.rotation_xyz((setup.lean, yaw, 0.0))[:3, :3]
    normal, e_u, e_v = rotation @ [0.0, 0.0, 1.0], rotation @ [1.0, 0.0, 0.0], rotation @ [0.0, -1.0, 0.0]
    anchor = np.array([0.0, 0.0, -1.0])  # the wall passes through this point

    # Where the frame's corner rays meet the wall, in wall coordinates (s along u, t along v) from the anchor.
    # A projective map takes the frame's rectangle to a convex quadrilateral while no pixel sees past the
    # horizon, so the corners bound the visible part of the wall.
    hits, distances = [], []
    for x in (0.0, w - 1.0):
        for y in (0.0, h - 1.0):
            d = _pixel_direction(setup, x, y)
            denom = float(d @ normal)
            if denom < 0.0:  # the ray meets the wall's front in front of the eye
                t = float(anchor @ normal) / denom
                hits.append(((t * d - anchor) @ e_u, (t * d - anchor) @ e_v))
                distances.append(t)
    horizon = len(hits) < 4
    hits = np.array(hits or [(0.0, 0.0)])  # no corner sees the wall's front: anchor the texture at the anchor point
    distances = distances or [1.0]
    unit = 1.0 / setup.texels_per_unit
    lo = hits.min(0) - (setup.offset + MARGIN_TEXELS) * unit
    # The far side gets a tenth of the visible extent more: near edge-on, one pixel there spans more than any
    # margin in texels, and the rasteriser must still cover the frame's last pixel.
    hi = hits.max(0) + MARGIN_TEXELS * unit + 0.1 * (hits.max(0) - hits.min(0))
    if horizon:  # past the horizon the wall has no far edge in view: any finite extent will do
        hi = np.maximum(hi, lo + 1e3)
    size = hi - lo
    centre = anchor + (lo[0] + hi[0]) / 2.0 * e_u + (lo[1] + hi[1]) / 2.0 * e_v
    uv_scale = size * setup.texels_per_unit / setup.texture_size
    camera = _camera(setup, far=2.0 * max(distances) + 10.0)
    quad = Quad(setup, camera, (w, h), yaw, (float(size[0]), float(size[1])), tuple(float(c) for c in centre),
                (setup.lean, yaw, 0.0), (float(uv_scale[0]), float(uv_scale[1])), np.zeros((3, 3)), horizon)
    return _with_coefficients(quad)


def _with_coefficients(quad: Quad) -> Quad:
    """``quad`` with K from its mesh (meshes.quad), model matrix, camera and viewport."""
    vertices = meshes.quad(*quad.size).astype(np.float64)
    position, uv = vertices[:, 0:3], vertices[:, 10:12]

    def corner(u: float, v: float) -> np.ndarray:
        return position[np.flatnonzero((uv[:, 0] == u) & (uv[:, 1] == v))[0]]

    p00, p10, p01 = corner(0, 0), corner(1, 0), corner(0, 1)
    texels = quad.setup.texture_size * np.asarray(quad.uv_scale)  # texels across the quad
    # local position = p00 + u * (p10 - p00) / texels_u + v * (p01 - p00) / texels_v, as a 4x3 map of (u, v, 1)
    local = np.zeros((4, 3))
    local[:3, 0], local[:3, 1], local[:3, 2], local[3, 2] = (p10 - p00) / texels[0], (p01 - p00) / texels[1], p00, 1.0
    model = cam.translation(quad.position) @ cam.rotation_xyz(quad.rotation)
    clip = _view_projection(quad.camera, quad.frame) @ model @ local
    to_screen = _viewport(quad.frame) @ clip[[0, 1, 3]]
    k = check_coefficients(np.linalg.inv(to_screen))
    return Quad(**{**quad.__dict__, "coefficients": k})


# --- the float64 reference -------------------------------------------------------------------------------------


def numerators(coefficients: np.ndarray, spans: Spans) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u', v', q') of every pixel of ``spans``, float64 (R, L)."""
    k = np.asarray(coefficients, np.float64)
    x, y = spans.pixels()
    return tuple(k[i, 0] * x + k[i, 1] * y + k[i, 2] for i in range(3))


#: The span clip's guard band on q, in float32 half-ulps of the span's largest term: the rounding bound of a running
#: sum of L steps (one half-ulp each), the coefficient rounding over the span (as much again) and a few for the start.
GUARD_STARTS = 8


def defined_range(coefficients: np.ndarray, spans: Spans) -> tuple[np.ndarray, np.ndarray]:
    """Per span, the pixels n in [first, end) that every method computes (float64 span setup, as a rasteriser
    clips): q >= the guard band (below it no float32 form knows the sign of q) and |u|, |v| <= UMAX / 2. The forms
    are linear along the span, so each condition holds on an interval of n; outside it pixels are flagged whatever
    a method computes there. Inside it the float64 texel is defined, so no unflagged pixel is ever undefined."""
    k = np.asarray(coefficients, np.float64)
    x0, y = spans.x0.astype(np.float64), spans.y.astype(np.float64)
    last = spans.length - 1
    start = k[:, 0:1] * x0 + k[:, 1:2] * y + k[:, 2:3]  # (3, R): each form at n = 0; it grows by k[:, 0] per pixel
    peak = np.max([np.abs(start[2]), np.abs(start[2] + k[2, 0] * last), np.abs(k[2, 1] * y),
                   np.full(x0.shape, abs(k[2, 2])), np.abs(k[2, 0] * (np.abs(x0) + last))], axis=0)
    guard = (2 * spans.length + GUARD_STARTS) * 2.0**-24 * peak
    half = UMAX / 2
    # each condition as c0 + c1 n >= 0
    conditions = [(start[2] - guard, np.full(x0.shape, k[2, 0]))]
    for i in (0, 1):
        for sign in (1.0, -1.0):
            conditions.append((half * start[2] - sign * start[i], np.full(x0.shape, half * k[2, 0] - sign * k[i, 0])))
    lo, hi = np.zeros(x0.shape), np.full(x0.shape, float(last))
    for c0, c1 in conditions:
        with np.errstate(divide="ignore", invalid="ignore"):
            root = -c0 / c1
        lo = np.where(c1 > 0, np.maximum(lo, root), lo)
        hi = np.where(c1 < 0, np.minimum(hi, root), hi)
        hi = np.where((c1 == 0) & (c0 < 0), -1.0, hi)  # never holds
    first = np.clip(np.ceil(lo), 0, spans.length).astype(np.int64)
    end = np.clip(np.floor(hi) + 1, 0, spans.length).astype(np.int64)
    return first, np.maximum(end, first)


def inside(coefficients: np.ndarray, spans: Spans) -> np.ndarray:
    """(R, L) bool: the pixels of ``defined_range``."""
    first, end = defined_range(coefficients, spans)
    n = np.arange(spans.length)
    return (n >= first[:, None]) & (n < end[:, None])


def valid(wu: np.ndarray, wv: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Pixels whose texel is defined: in front of the eye (q > 0) and |u|, |v| <= UMAX. Written so that NaN fails."""
    return (q > 0) & (np.abs(wu) <= UMAX * q) & (np.abs(wv) <= UMAX * q)


@dataclass(frozen=True)
class Reference:
    """Float64 u, v (texels) of every pixel, where they are defined, and the texel footprint of each pixel."""

    u: np.ndarray  # (R, L) float64, 0 where not valid
    v: np.ndarray
    valid: np.ndarray  # (R, L) bool
    footprint: np.ndarray  # (R, L) texels per pixel step (the larger of the x and y steps); inf where not valid


def reference(coefficients: np.ndarray, spans: Spans) -> Reference:
    k = np.asarray(coefficients, np.float64)
    wu, wv, q = numerators(k, spans)
    ok = valid(wu, wv, q)
    safe_q = np.where(ok, q, 1.0)
    u, v = np.where(ok, wu / safe_q, 0.0), np.where(ok, wv / safe_q, 0.0)
    # d(w/q)/dx = (A q - D w) / q^2, likewise for y.
    steps = [np.hypot((k[0, c] - k[2, c] * u) / safe_q, (k[1, c] - k[2, c] * v) / safe_q) for c in (0, 1)]
    footprint = np.where(ok, np.maximum(*steps), np.inf)
    return Reference(u, v, ok, footprint)


def middle_footprint(setup: Setup) -> float:
    """The texel footprint (``Reference.footprint``) of the frame's middle pixel (column L // 2 of the middle row)."""
    quad = build(setup)
    middle = Spans(np.array([setup.span_length // 2]), np.array([setup.rows // 2]), 1)
    return float(reference(quad.coefficients, middle).footprint[0, 0])


def at_footprint(setup: Setup, texels_per_pixel: float) -> Setup:
    """``setup`` with the texel density that gives its middle pixel a footprint of ``texels_per_pixel`` texels.
    Texel coordinates are the wall's position times the density (plus the offset), so the footprint scales with it
    exactly: spans of any length then sample the texture alike, and their coordinates grow with the length, as a
    longer span over the same texture reaches further."""
    if not (math.isfinite(texels_per_pixel) and texels_per_pixel > 0):
        raise InputError(f"texels_per_pixel = {texels_per_pixel!r}: expected a positive number")
    scale = texels_per_pixel / middle_footprint(setup)
    return replace(setup, texels_per_unit=setup.texels_per_unit * scale)


# --- the same quad for the renderer ---------------------------------------------------------------------------


def scene_toml(quad: Quad) -> str:
    """A scene with just the quad (constant albedo, ``basic``), for the hardware rasteriser's uv."""
    c = quad.camera

    def vec(values) -> str:
        return "[" + ", ".join(repr(float(x)) for x in values) + "]"

    return f"""
[scene]
name = "perspective-study"
techniques = ["basic"]
[camera]
position = {vec(c.position)}
target = {vec(c.target)}
up = {vec(c.up)}
fov = 60.0
near = {c.near!r}
far = {c.far!r}
[materials.wall]
albedo = [0.5, 0.5, 0.5]
uv_scale = {vec(quad.uv_scale)}
[[objects]]
type = "quad"
material = "wall"
size = {vec(quad.size)}
position = {vec(quad.position)}
rotation = {vec(quad.rotation)}
"""
