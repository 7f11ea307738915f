"""The map kinds: one frozen entry per kind (options, CPU and GPU functions, cross-check tolerance, writer)."""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from wgpuviewer.core.compute import source_hash
from wgpuviewer.core.errors import UserError

from . import cone as cn
from . import cpu, gpu, io
from . import distance as dist
from . import refined as rf


@dataclass(frozen=True)
class Option:
    name: str
    default: Any
    type: type
    help: str
    choices: tuple | None = None
    lo: float | None = None
    hi: float | None = None

    def validate(self, kind: str, value: Any) -> Any:
        try:
            v = self.type(value)
            if self.type is int and isinstance(value, float) and not float(value).is_integer():
                raise ValueError
        except (TypeError, ValueError):
            raise UserError(f"{kind}: option {self.name}={value!r} is not a valid {self.type.__name__}") from None
        if self.type is float and not math.isfinite(v):
            raise UserError(f"{kind}: option {self.name} must be finite, got {value!r}")
        if self.choices is not None and v not in self.choices:
            raise UserError(f"{kind}: option {self.name}={value!r}; expected one of {', '.join(map(str, self.choices))}")
        if (self.lo is not None and v < self.lo) or (self.hi is not None and v > self.hi):
            raise UserError(f"{kind}: option {self.name}={value!r} out of range [{self.lo}, {self.hi}]")
        return v


@dataclass(frozen=True)
class Comparison:
    max_diff: float
    mean_diff: float
    ok: bool
    detail: str = ""


@dataclass(frozen=True)
class Case:
    """Option values the kind's GPU path is cross-checked on against its CPU twin (tests/maptools), on every test
    map of at most ``max_texels`` texels (None: all; a bound keeps slow CPU twins to small maps)."""

    options: dict
    max_texels: int | None = None


@dataclass(frozen=True)
class Kind:
    name: str
    description: str
    options: tuple[Option, ...]
    cpu: Callable
    gpu: Callable
    compare: Callable[[Any, Any, dict], Comparison]
    tolerance: str
    writer: Callable[[Any, Any, str, int], None]  # (file object, result, extension, bits)
    extensions: tuple[str, ...]  # first = default for the batch tool
    check: Callable[[dict], None] = field(default=lambda opts: None)
    cases: tuple[Case, ...] = ()  # its GPU-vs-CPU cross-checks; every kind has some (tests/maptools)

    @property
    def kernels(self) -> tuple[str, ...]:
        """The WGSL files (``wgsl/maps/``) its GPU path runs."""
        return self.gpu.kernels

    def source_hash(self) -> str:
        """sha256 over the composed source of each of its kernels: part of every cache key of the kind, so an
        edited kernel (or a file it includes) never serves a map built by the old one."""
        h = hashlib.sha256()
        for file in self.kernels:
            h.update(source_hash(gpu.kernel_source(file)).encode())
        return h.hexdigest()

    def resolve(self, options: dict) -> dict:
        """Options with defaults filled in and validated; unknown names are a UserError."""
        known = {o.name: o for o in self.options}
        unknown = sorted(set(options) - set(known))
        if unknown:
            raise UserError(f"{self.name}: unknown option(s) {', '.join(unknown)}; "
                            f"known: {', '.join(known) or 'none'}")
        out = {o.name: o.validate(self.name, options.get(o.name, o.default)) for o in self.options}
        self.check(out)
        return out


# -- comparisons ------------------------------------------------------------------------------------

def _compare_normal(a, b, opts) -> Comparison:
    d = np.abs(np.asarray(a, np.float64) - np.asarray(b, np.float64))
    mx = float(d.max()) if d.size else 0.0
    return Comparison(mx, float(d.mean()) if d.size else 0.0, mx <= NORMAL_TOL)


def _compare_complexity(a, b, opts) -> Comparison:
    d = np.abs(a.astype(np.int32) - b.astype(np.int32))
    mx = int(d.max()) if d.size else 0
    frac = float((d > 0).mean()) if d.size else 0.0
    step = math.ceil(255 / (opts["levels"] - 1))
    ok = mx <= step and frac <= COMPLEXITY_MAX_FLIPPED
    return Comparison(float(mx), float(d.mean()) if d.size else 0.0, ok,
                      f"{frac:.2e} of texels differ (allowed {COMPLEXITY_MAX_FLIPPED:g}, by at most one level = {step})")


def _compare_maxmip(a, b, opts) -> Comparison:
    if len(a) != len(b) or any(x.shape != y.shape for x, y in zip(a, b)):
        return Comparison(math.inf, math.inf, False, "level count or shapes differ")
    diffs = [np.abs(x.astype(np.float64) - y) for x, y in zip(a, b)]
    mx = max(float(d.max()) for d in diffs)
    mean = float(np.mean([d.mean() for d in diffs]))
    return Comparison(mx, mean, mx == 0.0, f"{len(a)} levels")


#: Normal components: float rounding of sqrt/division differs by a few ULP between GPU and numpy.
NORMAL_TOL = 1e-5
#: Complexity: sqrt, division and pow are not correctly rounded on every GPU; a difference of one ULP
#: before quantisation can flip a texel to the neighbouring level. Allowed: one level, on <= 0.1 % of texels.
COMPLEXITY_MAX_FLIPPED = 1e-3


def _check_complexity(o: dict) -> None:
    if o["levels"] < 2:
        raise UserError(f"complexity: levels must be >= 2 (step = 1/(levels-1)), got {o['levels']}")
    if o["dilate_kernel"] % 2 == 0:
        raise UserError(f"complexity: dilate_kernel must be odd, got {o['dilate_kernel']}")
    if cpu.dilation_radius(o["dilate_kernel"], o["iterations"]) > 1024:
        raise UserError("complexity: dilation radius (dilate_kernel//2 * iterations) must be <= 1024")


#: Plain distance volumes: absolute difference in texel-metric units (float32 GPU arithmetic vs float64 CPU; measured
#: <= 1e-5 on lavapipe). Far below the STORE_MARGIN (1e-3) that every stored value already subtracts for rounding.
DISTANCE_TOL = 1e-4
#: Refined volumes (float16, rounded down): at most one float16 step of the larger value apart, or DISTANCE_TOL,
#: on all voxels (float32 vs float64 arithmetic may round the same value to neighbouring float16 numbers).
REFINED_REL_TOL = 2.0 ** -10


def _compare_distance(a, b, opts) -> Comparison:
    if np.shape(a) != np.shape(b):
        return Comparison(math.inf, math.inf, False, "shapes differ")
    d = np.abs(np.asarray(a, np.float64) - np.asarray(b, np.float64))
    mx = float(d.max()) if d.size else 0.0
    return Comparison(mx, float(d.mean()) if d.size else 0.0, mx <= DISTANCE_TOL)


def _compare_refined(a, b, opts) -> Comparison:
    if np.shape(a) != np.shape(b):
        return Comparison(math.inf, math.inf, False, "shapes differ")
    a64, b64 = np.asarray(a, np.float64), np.asarray(b, np.float64)
    d = np.abs(a64 - b64)
    allowed = np.maximum(DISTANCE_TOL, REFINED_REL_TOL * np.maximum(a64, b64))
    frac = float((d > 0).mean()) if d.size else 0.0
    return Comparison(float(d.max()) if d.size else 0.0, float(d.mean()) if d.size else 0.0,
                      bool((d <= allowed).all()), f"{frac:.2e} of values differ at all")


#: Cone ratios: relative difference (float32 GPU arithmetic vs float64 CPU, both then lose the 2^-12 store margin).
CONE_REL_TOL = 1e-5
#: ... on all but this fraction of texels (a "may exit" decision inside the float band can flip; either result is
#: conservative). Measured 0 on lavapipe.
CONE_MAX_FLIPPED = 5e-3


def _compare_cone(a, b, opts) -> Comparison:
    if np.shape(a) != np.shape(b):
        return Comparison(math.inf, math.inf, False, "shapes differ")
    a64, b64 = np.asarray(a, np.float64), np.asarray(b, np.float64)
    rel = np.abs(a64 - b64) / np.maximum(np.maximum(a64, b64), 1e-6)
    frac = float((rel > CONE_REL_TOL).mean()) if rel.size else 0.0
    return Comparison(float(rel.max()) if rel.size else 0.0, float(rel.mean()) if rel.size else 0.0,
                      frac <= CONE_MAX_FLIPPED,
                      f"relative; {frac:.2e} of texels differ by > {CONE_REL_TOL:g} (allowed {CONE_MAX_FLIPPED:g})")


_VOLUME_OPTIONS = (
    Option("slices", 16, int, "depth slices Dz of the volume (t in [0, 1])", lo=1, hi=256),
    Option("height_scale", 0.05, float, "relief depth S in UV units the map is built for (metric: depth x S*W)",
           lo=1e-3, hi=1.0),
    Option("subcells", 4, int, "sub-cells per bilinear cell side of the outer solid (1 = the cell-min solid)",
           choices=dist.SUBCELLS),
)

BORDER_HELP = "border handling: repeat (wrap, tiling textures), clamp, reflect (OpenCV's reflect-101)"

KINDS: dict[str, Kind] = {
    "normal": Kind(
        name="normal",
        description="unit tangent-space normals (H,W,3) from Sobel 3x3 gradients of the height map",
        options=(
            Option("strength", 1.0, float, "gradient scale: slope = strength * height units per texel", lo=0.0, hi=1e6),
            Option("y", "opengl", str, "y convention: opengl (+y towards row 0, green up) or directx (+y = +v, "
                   "increasing row)", choices=("opengl", "directx")),
            Option("border", "repeat", str, BORDER_HELP, choices=cpu.BORDERS),
        ),
        cpu=cpu.normal, gpu=gpu.normal, compare=_compare_normal,
        tolerance=f"max |component difference| <= {NORMAL_TOL:g}",
        writer=io.write_normal, extensions=(".png", ".npy"),
        cases=(*(Case({"border": b}) for b in cpu.BORDERS), Case({"y": "directx", "strength": 4.0})),
    ),
    "complexity": Kind(
        name="complexity",
        description="complexity map of the adaptive-POM thesis (Sobel magnitude, dilation, gamma, quantised levels), 8-bit",
        options=(
            Option("ksize", 3, int, "Sobel kernel size (listing 3; 5 also allowed)", choices=(3, 5)),
            Option("dilate_kernel", 3, int, "dilation kernel size (listing 3, text 5)", lo=1, hi=99),
            Option("iterations", 5, int, "dilation iterations (listing 5)", lo=0, hi=1024),
            Option("gamma", 0.8, float, "gamma exponent (listing 0.8, text 0.9)", lo=1e-3, hi=100.0),
            Option("levels", 24, int, "number of quantisation levels N >= 2 (listing 24)", lo=-(2**31), hi=4096),
            Option("border", "reflect", str, BORDER_HELP + "; dilation wraps only with repeat", choices=cpu.BORDERS),
        ),
        cpu=cpu.complexity, gpu=gpu.complexity, compare=_compare_complexity,
        tolerance=f"at most one quantisation level on <= {COMPLEXITY_MAX_FLIPPED:g} of texels (exact on lavapipe)",
        writer=io.write_complexity, extensions=(".png", ".npy"), check=_check_complexity,
        cases=(Case({"border": "reflect"}), Case({"border": "repeat"})),
    ),
    "maxmip": Kind(
        name="maxmip",
        description="maximum pyramid: level 0 = height, each parent = max of the children it covers, down to 1x1",
        options=(),
        cpu=cpu.maxmip, gpu=gpu.maxmip, compare=_compare_maxmip,
        tolerance="exact (max is exact)",
        writer=io.write_maxmip, extensions=(".npz",), cases=(Case({}),),
    ),
    "distance": Kind(
        name="distance",
        description="3D distance map (Donnelly 2005), float32 (Dz, H, W): per voxel the distance from the voxel box to an "
                    "outer solid of sub-cell columns, in texels of u (v scaled by W/H, depth by S*W); a safe step for "
                    "a nearest lookup anywhere in the voxel; periodic in u, v",
        options=_VOLUME_OPTIONS,
        cpu=dist.distance, gpu=gpu.distance, compare=_compare_distance,
        tolerance=f"max |difference| <= {DISTANCE_TOL:g} texel",
        writer=io.write_volume, extensions=(".npy",),
        cases=(Case({"slices": 4, "height_scale": 0.3}, 2048), Case({"slices": 3, "subcells": 1}, 2048)),
    ),
    "distance_refined": Kind(
        name="distance_refined",
        description="direction-binned refined distance map (Romanyuk et al. 2017), float16 (V, Dz, H, W) rounded down: one "
                    "volume per bin of ray directions (azimuth sectors x polar bands of the view cone) with a safe "
                    "step for every ray of that bin, then the plain map (steeper rays); nearest lookups",
        options=_VOLUME_OPTIONS + (
            Option("max_angle", 85.0, float, "half-angle of the binned view cone, degrees from the normal",
                   lo=1.0, hi=89.0),
            Option("sectors", 4, int, "azimuth sectors (with bands 1: 1 = the single cone of the paper)",
                   choices=rf.SECTOR_CHOICES),
            Option("bands", 8, int, "polar bands, edges of equal cosine ratio: cos edge_k = cos(max_angle)^(k/bands)",
                   lo=1, hi=rf.MAX_BANDS),
            Option("reach", 16.0, float, "columns farther than this (texels, horizontally) are not looked at; "
                   "values are capped near it", lo=1.0, hi=256.0),
            Option("visibility", "off", str, "the paper's visibility condition: on = each voxel bounded only for "
                   "the directions that can reach it unblocked from the top (with sectors 1, bands 1: the paper's map)",
                   choices=rf.VISIBILITY_CHOICES),
        ),
        cpu=rf.distance_refined, gpu=gpu.distance_refined, compare=_compare_refined,
        tolerance=f"|difference| <= max({DISTANCE_TOL:g} texel, one float16 step) on every value",
        writer=io.write_volume, extensions=(".npy",),
        cases=(Case({"slices": 4, "height_scale": 0.3, "sectors": 2, "bands": 2}, 2048),
               Case({"slices": 4, "height_scale": 0.3, "sectors": 4, "bands": 5, "visibility": "on"}, 2048)),
    ),
    "cone": Kind(
        name="cone",
        description="relaxed cone map (Policarpo & Oliveira), float32 (H, W): cone ratio in texels of u per "
                    "unit of layer depth t, conservative for the bilinear surface (docs/maps.md)",
        options=(
            Option("max_ratio", 16.0, float, "largest stored ratio (texels per unit t); bounds the search to "
                   "about (2 max_ratio)^2 cells per texel", lo=0.25, hi=cn.PNG_SCALE),
            Option("filter", "bilinear", str, "lookup the tracer uses: bilinear (3x3 min; safe for bilinear and "
                   "nearest lookups) or nearest (larger cones, nearest lookups only)", choices=cn.FILTERS),
        ),
        cpu=cn.cone, gpu=gpu.cone, compare=_compare_cone,
        tolerance=f"relative difference <= {CONE_REL_TOL:g} on all but {CONE_MAX_FLIPPED:g} of texels",
        writer=io.write_cone, extensions=(".npy", ".png"),
        cases=(Case({"filter": "nearest"}, 2048), Case({"filter": "bilinear"}, 2048)),
    ),
}


def get_kind(name: str) -> Kind:
    if name not in KINDS:
        raise UserError(f"unknown map kind {name!r}; expected one of {', '.join(KINDS)}")
    return KINDS[name]


def _option_cell(o: Option) -> str:
    return f"`{o.name}` {o.default:g}" if isinstance(o.default, float) else f"`{o.name}` {o.default}"


def markdown_table() -> str:
    """The README's map-kind table: kind, what it is, its options (defaults), its kernels, GPU vs CPU tolerance."""
    rows = ["| kind | what | options (default) | kernels (`wgsl/maps/`) | GPU vs CPU |", "|---|---|---|---|---|"]
    for k in KINDS.values():
        options = ", ".join(map(_option_cell, k.options)) or "—"
        kernels = ", ".join(f"`{f}`" for f in k.kernels)
        cells = (f"`{k.name}`", k.description, options, kernels, k.tolerance)
        rows.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")  # a | in a cell is escaped
    return "\n".join(rows)
