"""The technique registry: one entry per WGSL file in ``wgsl/techniques/``.

An entry names what a technique needs (textures and maps, by their slot names in ``maps.MAP_SLOTS``), its
parameters with defaults and ranges, and whether it is a ray search (then its WGSL defines ``trace`` and the
probe can run it). Everything WGSL must agree on is generated from the entry (``shaders.interface``): the
``TraceParams`` uniform (the common fields, then the parameters, then the fixed values, each of its own WGSL type:
f32, u32 or i32), one binding line per texture it needs, and ``NAME_MIN`` / ``NAME_MAX`` constants for its numeric
parameters, in the parameter's type.

May import: ``wgpuviewer.core``, ``maptools`` and ``wgpuviewer.relief`` (a technique's maps and measurements).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from wgpuviewer.core.errors import UserError

#: TraceParams fields every technique has, with their WGSL types: the material's relief scale, its depth map's size
#: in texels (for the mip level) and depth range (maps.depth_range: the layer searches march only that range,
#: common/trace.wgsl's relief_range). The technique's parameters and fixed values follow.
COMMON_TRACE_FIELDS = (("height_scale", "f32"), ("depth_width", "u32"), ("depth_height", "u32"), ("depth_min", "f32"),
                       ("depth_max", "f32"))

#: Full heat of the cost view for techniques without a layer bound (fetches per pixel).
COMMON_COST_SCALE = 64.0

#: Hard cap on any layer count (generated into every technique's WGSL as ``MAX_LAYERS``).
MAX_LAYERS = 1024

#: quadmax's default step cap (auto's quadmax candidate runs with it too).
QUADMAX_STEPS = 1024
#: quadmax's default start-level offset (quadmax_pom's skip uses it too).
QUADMAX_TOP_OFFSET = -2
#: The relaxed cone map the cone tracer reads (maps.py builds it): its widest stored cone (texels of u per unit t;
#: the build costs O(max_ratio^2) per texel) and its lookup (cone.wgsl reads the nearest texel).
CONE_MAX_RATIO = 32.0
CONE_FILTER = "nearest"
#: cone.wgsl's bracket finish: halvings that bring a bracket to one cell (24: float32 t cannot be split further
#: anyway; a longer bracket ends flagged at its free end), and the cells a one-cell bracket crosses (one x and one
#: y border) plus the cell its start may round into.
CONE_HALVINGS_MAX = 24
CONE_FINISH_CELLS = 4
#: The grazing finish of distance and cone (common/maxmip_walk.wgsl): after this many slow steps (slow_step there) a
#: ray goes on with the max-pyramid walk, for at most PYRAMID_STEPS steps (four times maxmip's default cap: at 89.9
#: degrees a ray on the 256x256 bricks map needs more than 1024).
HANDOVER_STEPS = 8
PYRAMID_STEPS = 4096


@dataclass(frozen=True)
class Param:
    name: str
    default: float
    min: float
    max: float
    kind: type  # int, float or bool
    doc: str

    def validate(self, value, where: str):
        """Checked value, or UserError naming ``where`` (e.g. 'scene.toml: techniques.pom.layers')."""
        expected = {int: "an integer", float: "a number", bool: "true or false"}[self.kind]
        ok_type = isinstance(value, bool) if self.kind is bool else (
            isinstance(value, int) and not isinstance(value, bool)
            if self.kind is int
            else isinstance(value, (int, float)) and not isinstance(value, bool)
        )
        if not ok_type:
            raise UserError(f"{where} = {value!r}: expected {expected}")
        if self.kind is not bool and not (self.min <= value <= self.max):
            raise UserError(f"{where} = {value!r}: out of range, expected {self.min:g} to {self.max:g}")
        return self.kind(value)

    @property
    def wgsl_type(self) -> str:
        """Its type in the generated uniform and its NAME_MIN / NAME_MAX constants: f32 for a number, u32 for a flag
        (0 or 1) and for an integer whose range starts at 0 or above, i32 for one whose range goes below 0."""
        if self.kind is float:
            return "f32"
        return "i32" if self.kind is int and self.min < 0 else "u32"


#: The WGSL types a fixed TraceParams value may have: a count, a signed integer, a real number.
FIXED_TYPES = ("u32", "i32", "f32")


@dataclass(frozen=True)
class Fixed:
    """A TraceParams value fixed by the technique (not a user parameter), e.g. a property of the map it samples,
    with its WGSL type: ``u32`` (a count), ``i32`` (a signed integer) or ``f32`` (a real number)."""

    name: str
    value: int | float
    wgsl_type: str

    def __post_init__(self):
        if self.wgsl_type not in FIXED_TYPES:
            raise ValueError(f"fixed value {self.name!r}: type {self.wgsl_type!r} is not one of {', '.join(FIXED_TYPES)}")
        integer = isinstance(self.value, int) and not isinstance(self.value, bool)
        if self.wgsl_type != "f32" and not (integer and (self.wgsl_type == "i32" or self.value >= 0)):
            raise ValueError(f"fixed value {self.name!r} = {self.value!r} is not a {self.wgsl_type}")


class Parametrized:
    """A registry entry with ``params`` (a tuple of Param): lookup by name and the default values."""

    def param(self, name: str) -> Param:
        for p in self.params:
            if p.name == name:
                return p
        raise KeyError(name)

    def defaults(self) -> dict:
        return {p.name: p.kind(p.default) for p in self.params}


@dataclass(frozen=True)
class Technique(Parametrized):
    name: str
    key: str  # default keyboard key in the viewer
    description: str
    cost: str  # what it costs, for humans (README table, `wgpuviewer techniques`)
    textures: tuple[str, ...]  # slot names in maps.MAP_SLOTS: 'albedo', 'normal', 'depth' and derived maps
    params: tuple[Param, ...] = ()
    ray_search: bool = False
    #: The WGSL file: a name in wgsl/techniques/ (default NAME.wgsl) or an absolute path.
    wgsl: str = ""
    #: TraceParams values fixed by the technique (not user parameters), e.g. a property of the map it samples.
    fixed: tuple[Fixed, ...] = ()
    #: Ray searches: the most fetches one ray may count, given the parameters (the contract tests hold every
    #: ray-search technique to it).
    fetch_bound: Callable[[dict], int] | None = None
    #: Finds the first hit of the bilinear surface to float32 precision: never behind the float64 exact hit.
    exact: bool = False
    #: Ray searches: the fetch count the cost view draws as full heat, given the parameters (the search's own bound
    #: where its parameters give one, else ``common_cost_scale``, so techniques compare side by side).
    cost_view_scale: Callable[[dict], float] | None = None
    #: Ray searches: (lo, hi) of the layers view's grey (N - lo) / (hi - lo), given the parameters, for the
    #: ``layers`` count the trace reports (``no_layers`` for searches that report none).
    layers_view_range: Callable[[dict], tuple[float, float]] | None = None
    #: Ray searches: parameter overrides beyond the defaults that the contract tests (tests/relief/test_contracts.py)
    #: run too: each setting that takes another code path (a flag, a variant, a smallest count or cap).
    contract_params: tuple[dict, ...] = ()
    #: Why ``contract_params`` is empty, where it is (the defaults already take every code path).
    contract_exemption: str = ""
    #: Ray searches: the parameter overrides ``wgpuviewer accuracy`` measures (``{}``: the defaults).
    accuracy_settings: tuple[dict, ...] = ()

    @property
    def wgsl_file(self) -> str:
        """The file for the WGSL composer: relative to wgsl/, or absolute."""
        name = self.wgsl or f"{self.name}.wgsl"
        return name if name.startswith("/") else f"techniques/{name}"

    @property
    def trace_field_types(self) -> tuple[tuple[str, str], ...]:
        """(name, WGSL type) of this technique's TraceParams fields, in order: the common ones, the parameters
        (``Param.wgsl_type``), the fixed values (``Fixed.wgsl_type``)."""
        return (COMMON_TRACE_FIELDS + tuple((p.name, p.wgsl_type) for p in self.params)
                + tuple((f.name, f.wgsl_type) for f in self.fixed))

    @property
    def trace_fields(self) -> tuple[str, ...]:
        """Names of this technique's TraceParams fields, in order."""
        return tuple(name for name, _ in self.trace_field_types)

    def fixed_values(self) -> dict:
        """The fixed TraceParams values by name."""
        return {f.name: f.value for f in self.fixed}

    @property
    def needs_depth(self) -> bool:
        return "depth" in self.textures

    def cost_scale(self, params: dict) -> float:
        """Fetch count drawn as full heat in the cost view (``cost_view_scale``; the common scale for techniques
        that are not ray searches)."""
        return self.cost_view_scale(params) if self.cost_view_scale else COMMON_COST_SCALE

    def layer_range(self, params: dict) -> tuple[float, float]:
        """(lo, hi) of the layers view's grey (render.wgsl's layer_grey gets them in Frame): ``layers_view_range``,
        or (0, 1) for techniques that are not ray searches (they report no layers)."""
        return self.layers_view_range(params) if self.layers_view_range else no_layers(params)


def common_cost_scale(params: dict) -> float:
    """The cost view's scale for searches without a layer bound: one for all, so they compare side by side."""
    return COMMON_COST_SCALE


def no_layers(params: dict) -> tuple[float, float]:
    """The layers view's range for searches that report no layer count (their ``layers`` is 0)."""
    return 0.0, 1.0


#: The refined distance map's direction bins (maps.py builds it with these maptools distance_refined options; the
#: tracer picks a ray's volume from the same numbers, see distance.wgsl): azimuth sectors, polar bands (edges of
#: equal cosine ratio) and the binned cone's half-angle; steeper rays read the plain volume stored last. 85 rather
#: than 80 degrees: a benchmark frame centred at 80 degrees spans 79.3-80.7, and with an 80-degree cone its steeper
#: half read the plain volume (wall: -8 % instead of -42 % fetches); 85 costs no memory (measured: docs/maps.md).
REFINED_SECTORS = 4
REFINED_BANDS = 8
REFINED_MAX_ANGLE = 85.0



#: relief's cap on binary steps (its parameter's range; auto clamps the table's count to it).
RELIEF_BINARY_STEPS_MAX = 32
#: auto's relief candidates (linear steps, binary steps): POM's counts up to 32 with one or two halvings (no halving
#: is POM; a third saves 0.4 % of the table cost on the benchmark's maps, docs/techniques.md).
AUTO_RELIEF_STEPS = tuple((n, b) for n in (4, 6, 8, 12, 16, 24, 32) for b in (1, 2))
#: ``auto``'s candidates, cheapest first: (technique, parameter overrides). The shader runs each one's code
#: (basic: the entry point; parallax; pom_search with the layer count; relief_search with its linear and binary
#: steps; quadmax_search with the top offset); the probe measures each one as that technique (relief/autotable.py).
AUTO_CANDIDATES: tuple[tuple[str, dict], ...] = (
    ("basic", {}), ("parallax", {}),
    # the layer searches by their fetch bound less one (POM: layers; relief: linear + binary steps)
    *sorted((*(("pom", {"layers": n}) for n in (4, 6, 8, 12, 16, 24, 32, 48, 64)),
             *(("relief", {"linear_steps": n, "binary_steps": b}) for n, b in AUTO_RELIEF_STEPS)),
            key=lambda candidate: sum(candidate[1].values())),
    ("quadmax", {}),
)
#: auto's method ids in its table (auto.wgsl switches on them).
AUTO_METHODS = {"basic": 0, "parallax": 1, "pom": 2, "quadmax": 3, "relief": 4}
#: auto's view-angle bins: bin 0 is tan(angle) < AUTO_TAN0, bin i + 1 is [tan0 2^(i/k), tan0 2^((i+1)/k)) with
#: k = AUTO_BINS_PER_OCTAVE, up to AUTO_BINS bins (the last one open-ended): the search cost follows the ray's
#: reach tan(angle) * S * W, so the bins are even in its logarithm (about 88.7 degrees at the last edge).
AUTO_TAN0 = 2.0 ** -8
AUTO_BINS_PER_OCTAVE = 2
AUTO_BINS = 29
#: auto's error budgets (texels): 2^(AUTO_BUDGET_LOG2_MIN + j), j < AUTO_BUDGET_LEVELS; max_error picks the largest
#: one not above it.
AUTO_BUDGET_LOG2_MIN = -4
AUTO_BUDGET_LEVELS = 8


def _layer_search(name: str, key: str, description: str, accuracy_settings: tuple[dict, ...]) -> Technique:
    """steep and pom: the same layer march with the same parameter, bound and coverage (their WGSL differs in the
    finish)."""
    return Technique(
        name, key, description, "up to N+1 depth fetches", ("albedo", "normal", "depth"),
        (Param("layers", 16, 1, MAX_LAYERS, int, "layer count: the ray is tested at this many evenly spaced depths"),),
        ray_search=True, fetch_bound=lambda p: p["layers"] + 1, cost_view_scale=lambda p: p["layers"] + 1.0,
        layers_view_range=lambda p: (0.0, float(p["layers"])), contract_params=({"layers": 1},),
        accuracy_settings=accuracy_settings,
    )


def distance_fixed(sectors: int, bands: int, max_angle: float | None) -> tuple[Fixed, ...]:
    """TraceParams values of distance.wgsl for a texture of ``sectors`` x ``bands`` direction volumes plus the plain
    one (max_angle = None: the plain map alone, one volume every ray reads; steep_cos -2: no ray is steeper)."""
    if max_angle is None:
        sectors, bands, steep_cos, volumes = 1, 1, -2.0, 1
    else:
        steep_cos, volumes = math.cos(math.radians(max_angle)), sectors * bands + 1
    return (Fixed("sectors", sectors, "u32"), Fixed("bands", bands, "u32"), Fixed("steep_cos", steep_cos, "f32"),
            Fixed("volumes", volumes, "u32"))


DISTANCE_COST = (f"one volume fetch per step + one 2x2 gather per exact cell; a grazing ray's pyramid walk up to "
                 f"{PYRAMID_STEPS}")


def distance_fetch_bound(p: dict) -> int:
    return 2 * p["iterations"] + PYRAMID_STEPS


#: The TraceParams values of the grazing finish (distance and cone).
GRAZING_FINISH = (Fixed("handover_steps", HANDOVER_STEPS, "u32"), Fixed("pyramid_steps", PYRAMID_STEPS, "u32"))


TECHNIQUES: dict[str, Technique] = {
    t.name: t
    for t in (
        Technique(
            "basic", "1", "Basic texturing: albedo at the interpolated UV, flat surface normal.",
            "1 albedo fetch", ("albedo",),
        ),
        Technique(
            "normal", "2", "Normal mapping: per-pixel normals from the normal map, no displacement.",
            "albedo + normal fetch", ("albedo", "normal"),
        ),
        Technique(
            "parallax", "3",
            "Parallax (offset) mapping: uv' = uv - V.xy/V.z * depth(uv) * scale; with offset limiting "
            "the division by V.z is dropped (Welsh), which bounds the offset at grazing angles.",
            "1 depth fetch", ("albedo", "normal", "depth"),
            (Param("offset_limiting", False, 0, 1, bool, "drop the 1/V.z factor (bounded offset)"),),
            ray_search=True, fetch_bound=lambda p: 1, cost_view_scale=common_cost_scale, layers_view_range=no_layers,
            contract_params=({"offset_limiting": True},), accuracy_settings=({}, {"offset_limiting": True}),
        ),
        _layer_search(
            "steep", "4",
            "Steep parallax mapping: march N depth layers along the view ray, stop at the first layer "
            "below the surface.",
            ({"layers": 32},),
        ),
        _layer_search(
            "pom", "5",
            "Parallax occlusion mapping: steep parallax, then linear interpolation between the last two "
            "layers (guarded against a zero denominator).",
            ({"layers": 8}, {"layers": 32}, {"layers": 256}),
        ),
        Technique(
            "pom_adaptive", "6",
            "Adaptive POM (thesis): layer count from the view angle, F = (1-|V.z|)^0.8, and the complexity map C "
            "at the entry uv: N = int(mix(mix(Nmin, Nmax/2, F), mix(Nmin, Nmax, F), C)) (truncated, as the "
            "thesis' int()); then the POM search. angle_only: three.js/Godot's N = int(mix(Nmax, Nmin, |V.z|)).",
            "up to N+1 depth fetches (+1 complexity fetch, not counted)", ("albedo", "normal", "depth", "complexity"),
            (
                Param("min_layers", 4, 1, MAX_LAYERS, int, "Nmin: layers at a head-on view"),
                Param("max_layers", 32, 1, MAX_LAYERS, int, "Nmax: layers at a grazing view on a complex region"),
                Param("angle_only", False, 0, 1, bool, "ignore the complexity map (three.js/Godot variant)"),
            ),
            ray_search=True, fetch_bound=lambda p: max(p["min_layers"], p["max_layers"]) + 1,
            cost_view_scale=lambda p: p["max_layers"] + 1.0,
            layers_view_range=lambda p: (float(p["min_layers"]), float(p["max_layers"])),
            contract_params=({"angle_only": True}, {"min_layers": 8, "max_layers": 2}),
            accuracy_settings=({}, {"angle_only": True}),
        ),
        Technique(
            "relief", "7",
            "Relief mapping (Policarpo): linear search in equal depth steps, then binary search between the last "
            "step above the surface and the first below it, ended by the secant through the final bracket's ends "
            "(no extra fetch; with 0 binary steps this is POM).",
            "up to linear_steps+1+binary_steps depth fetches", ("albedo", "normal", "depth"),
            (
                Param("linear_steps", 16, 1, MAX_LAYERS, int, "linear search steps (depth layers)"),
                Param("binary_steps", 6, 0, RELIEF_BINARY_STEPS_MAX, int, "binary refinement steps (each halves the bracket)"),
            ),
            ray_search=True, fetch_bound=lambda p: p["linear_steps"] + 1 + p["binary_steps"],
            cost_view_scale=lambda p: p["linear_steps"] + 1.0 + p["binary_steps"],
            layers_view_range=lambda p: (0.0, float(p["linear_steps"])),
            contract_params=({"linear_steps": 1, "binary_steps": 0},),
            accuracy_settings=({}, {"linear_steps": 32, "binary_steps": 8}),
        ),
        Technique(
            "maxmip", "8",
            "Maximum-mipmap tracing (Romanyuk & Dudnyk 2018, modified MIP pyramid): descend a max pyramid over the "
            "bilinear cells from the top, skip nodes the ray passes above, climb back after a skip; solve the exact "
            "per-cell quadratic at the base. Finds the first hit of the bilinear surface to float32 precision (repeat "
            "addressing).",
            "pyramid texel per node + one 2x2 gather per base cell", ("albedo", "normal", "depth", "maxmip"),
            (Param("max_steps", 1024, 1, 65536, int, "cap on traversal steps (capped rays are flagged)"),),
            ray_search=True, fetch_bound=lambda p: p["max_steps"], exact=True,
            cost_view_scale=common_cost_scale, layers_view_range=no_layers,
            contract_params=({"max_steps": 8},), accuracy_settings=({},),
        ),
        Technique(
            "distance", "9",
            "Distance-map parallax (Donnelly): sphere tracing through a 3D map of safe radii (box-exact distance to a "
            "sub-cell outer solid); where the radius does not leave the current bilinear cell the cell is solved "
            "exactly and skipped if it holds no hit. A grazing ray finishes with maxmip's pyramid walk. Never passes a "
            "surface.",
            DISTANCE_COST, ("albedo", "normal", "depth", "distance", "maxmip"),
            (Param("iterations", 256, 1, 4096, int, "cap on steps (sphere steps + exact cells); capped rays flagged"),),
            ray_search=True, fixed=distance_fixed(1, 1, None) + GRAZING_FINISH, fetch_bound=distance_fetch_bound,
            exact=True,
            cost_view_scale=common_cost_scale, layers_view_range=no_layers,
            contract_params=({"iterations": 8},), accuracy_settings=({},),
        ),
        Technique(
            "distance_refined", "0",
            "Distance-map parallax on the direction-binned refined map (Romanyuk et al. 2017): the same tracer as distance "
            f"(distance.wgsl); the map has one volume per bin of ray directions ({REFINED_SECTORS} azimuth sectors x "
            f"{REFINED_BANDS} polar bands within {REFINED_MAX_ANGLE:g} degrees) with longer safe steps for "
            "the rays of that bin, and the plain volume for steeper rays. A ray picks its volume once.",
            DISTANCE_COST, ("albedo", "normal", "depth", "distance_refined", "maxmip"),
            (Param("iterations", 256, 1, 4096, int, "cap on steps (sphere steps + exact cells); capped rays flagged"),),
            ray_search=True, wgsl="distance.wgsl", fetch_bound=distance_fetch_bound, exact=True,
            fixed=distance_fixed(REFINED_SECTORS, REFINED_BANDS, REFINED_MAX_ANGLE) + GRAZING_FINISH,
            cost_view_scale=common_cost_scale, layers_view_range=no_layers,
            contract_params=({"iterations": 8},), accuracy_settings=({},),
        ),
        Technique(
            "quadmax", "-",
            "Max-quadtree tracing (maxmip with three changes): the walk starts at level floor(log2(reach in texels)) "
            "+ top_offset, a node texel holds its four children's maxima (moving to a sibling or back up is free), and "
            "a 2x2-cell leaf packs its 9 depths (14-bit, rounded towards the top) in one texel, solved exactly per "
            "cell. Never behind the first hit; early by at most the 6e-5 depth quantisation.",
            "one atlas texel per quad node read + one per leaf (at most 2 per step)",
            ("albedo", "normal", "depth", "quadmax"),
            (
                Param("top_offset", QUADMAX_TOP_OFFSET, -8, 8, int,
                      "start level = floor(log2(ray reach in texels)) + this (>= 1)"),
                Param("max_steps", QUADMAX_STEPS, 1, 65536, int, "cap on traversal steps (capped rays are flagged)"),
            ),
            ray_search=True, fetch_bound=lambda p: 2 * p["max_steps"],
            cost_view_scale=common_cost_scale, layers_view_range=no_layers,
            contract_params=({"top_offset": 3, "max_steps": 8}, {"top_offset": -8}), accuracy_settings=({},),
        ),
        Technique(
            "quadmax_pom", "-",
            "Hybrid (the quadtree-displacement idea): quadmax's exact walk cut after skip_steps steps, then POM with "
            "`layers` layers over the rest of the ray from the last point the walk proved free. Exact where the walk "
            "meets the surface in time; otherwise approximate (the layers can step over thin features), error "
            "measured by the probe and the benchmark.",
            "at most 2*skip_steps quadmax atlas fetches, then layers + 1 depth fetches",
            ("albedo", "normal", "depth", "quadmax"),
            (
                Param("skip_steps", 8, 1, 64, int, "quadmax steps before the POM finish"),
                Param("layers", 16, 1, MAX_LAYERS, int, "POM layers over the rest of the ray"),
            ),
            ray_search=True, fixed=(Fixed("top_offset", QUADMAX_TOP_OFFSET, "i32"),),
            fetch_bound=lambda p: 2 * p["skip_steps"] + p["layers"] + 1,
            cost_view_scale=lambda p: p["layers"] + 1.0, layers_view_range=lambda p: (0.0, float(p["layers"])),
            contract_params=({"skip_steps": 1, "layers": 1},), accuracy_settings=({}, {"skip_steps": 16}),
        ),
        Technique(
            "auto", "-",
            "The error budget as a technique: per pixel, the view angle picks the cheapest candidate (basic, "
            "parallax, POM 4-64 layers, relief 4-32 linear steps with 1 or 2 binary steps, quadmax) whose p97.5 UV "
            "error the probe measured within max_error on this material's own height map, at both ends of the "
            "angle bin (relief/autotable.py; cached with the maps).",
            "the chosen candidate's fetches (one table texel, not counted)",
            ("albedo", "normal", "depth", "quadmax", "auto_table"),
            (Param("max_error", 0.5, 2.0 ** AUTO_BUDGET_LOG2_MIN, 2.0 ** (AUTO_BUDGET_LOG2_MIN + AUTO_BUDGET_LEVELS - 1),
                   float, "UV error budget in texels (the table's budgets are powers of 2: the largest one not "
                   "above this is used)"),),
            ray_search=True,
            fixed=(Fixed("bin_tan0", AUTO_TAN0, "f32"), Fixed("bins_per_octave", AUTO_BINS_PER_OCTAVE, "u32"),
                   Fixed("budget_log2_min", AUTO_BUDGET_LOG2_MIN, "i32"), Fixed("quadmax_steps", QUADMAX_STEPS, "u32"),
                   Fixed("binary_steps_max", RELIEF_BINARY_STEPS_MAX, "u32")),
            fetch_bound=lambda p: max(TECHNIQUES[name].fetch_bound(resolve_params(TECHNIQUES[name], params))
                                      for name, params in AUTO_CANDIDATES if TECHNIQUES[name].ray_search),
            cost_view_scale=common_cost_scale,
            # the layers view shows the chosen candidate (1-based, cheapest first) instead of a layer count
            layers_view_range=lambda p: (1.0, float(len(AUTO_CANDIDATES))),
            contract_params=({"max_error": 2.0 ** AUTO_BUDGET_LOG2_MIN},
                             {"max_error": 2.0 ** (AUTO_BUDGET_LOG2_MIN + AUTO_BUDGET_LEVELS - 1)}),
            accuracy_settings=({"max_error": 0.25}, {"max_error": 0.5}, {"max_error": 1.0}),
        ),
        Technique(
            "cone", "-",
            "Robust relaxed cone stepping (Policarpo & Oliveira's relaxed cone map, conservative for the bilinear "
            "surface; Bán et al. 2024's rule: never step less than to the cell's border): each step either skips by "
            "a cone that leaves the current cell (proven free by the texel's footprint minimum) or solves the cell "
            "exactly and moves on; a cone step that ends in the relief is halved to one cell and solved exactly. "
            "Never passes a surface.",
            "1 packed cone texel per skip; 1 gather per solved cell (+ the texel where a cone could leave it); a bracket "
            f"adds up to {CONE_HALVINGS_MAX} halvings and {CONE_FINISH_CELLS} cells; a grazing ray's pyramid walk up "
            f"to {PYRAMID_STEPS}: at most 2*iterations + {CONE_HALVINGS_MAX + CONE_FINISH_CELLS + PYRAMID_STEPS}",
            ("albedo", "normal", "depth", "cone", "maxmip"),
            (Param("iterations", 128, 1, 4096, int, "cap on steps (cell solves + cone skips); capped rays flagged"),),
            ray_search=True, exact=True,
            fixed=(Fixed("max_ratio", CONE_MAX_RATIO, "f32"), Fixed("halvings_max", CONE_HALVINGS_MAX, "u32"),
                   Fixed("finish_cells", CONE_FINISH_CELLS, "u32"), *GRAZING_FINISH),
            fetch_bound=lambda p: 2 * p["iterations"] + CONE_HALVINGS_MAX + CONE_FINISH_CELLS + PYRAMID_STEPS,
            cost_view_scale=common_cost_scale, layers_view_range=no_layers,
            contract_params=({"iterations": 8},), accuracy_settings=({},),
        ),
    )
}


def get_technique(name: str, where: str = "technique") -> Technique:
    try:
        return TECHNIQUES[name]
    except KeyError:
        raise UserError(f"{where} = {name!r}: unknown technique; expected one of {', '.join(TECHNIQUES)}") from None


def resolve_params(technique: Technique, overrides: dict | None = None, where: str = "", kind: str = "technique") -> dict:
    """Defaults merged with checked overrides (unknown names are errors naming ``where``). Also for other registry
    entries with ``name``, ``params``, ``param()`` and ``defaults()`` (texture filters: ``kind="filter"``)."""
    values = technique.defaults()
    for name, value in (overrides or {}).items():
        key = f"{where}{name}" if where else f"{technique.name}.{name}"
        try:
            param = technique.param(name)
        except KeyError:
            known = ", ".join(p.name for p in technique.params) or "none"
            raise UserError(f"{key}: unknown parameter of {kind} {technique.name!r}; known: {known}") from None
        values[name] = param.validate(value, key)
    return values


def _param_cell(p: Param) -> str:
    if p.kind is bool:
        return f"`{p.name}` ({'on' if p.default else 'off'})"
    return f"`{p.name}` {p.default:g} ({p.min:g} to {p.max:g})"


def markdown_table() -> str:
    """The README's technique table: key, name, the maps it samples, what it costs, its parameters (default, range)."""
    rows = ["| key | name | needs | what it costs (fetches per ray) | parameters |", "|---|---|---|---|---|"]
    for t in TECHNIQUES.values():
        name = f"`{t.name}`" + (" (exact)" if t.exact else "")
        params = ", ".join(_param_cell(p) for p in t.params) or "—"
        rows.append(f"| {t.key} | {name} | {', '.join(t.textures)} | {t.cost} | {params} |")
    return "\n".join(rows)
