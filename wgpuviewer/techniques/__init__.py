"""The technique registry: the ``Technique`` type, what every technique's interface shares, and the discovery of
the technique folders.

A technique is one folder, ``wgpuviewer/techniques/NAME/``: its ``__init__`` exposes ``TECHNIQUE`` (the entry: what
it samples, by slot name, and the slots only it uses; its parameters with defaults and ranges; its fixed values;
whether it is a ray search, then its WGSL defines ``trace`` and the probe can run it) and ``NAME.wgsl`` beside it is
its shader. ``TECHNIQUES`` finds the folders on first use (``pkgutil`` over this package's search path, no list to
edit) and orders them by ``Technique.order``. ``shared`` holds what several folders use (a folder never imports
another). Everything WGSL must agree on is generated from the entry (``relief.shaders.interface``): the
``TraceParams`` uniform (the common fields, then the parameters, then the fixed values, each of its own WGSL type:
f32, u32 or i32), one binding line per texture it needs, and ``NAME_MIN`` / ``NAME_MAX`` constants for its numeric
parameters, in the parameter's type.

May import: ``wgpuviewer.core`` only (this module and ``shared``). A technique folder may import
``wgpuviewer.core``, this registry and ``shared``, ``maptools`` (its maps' options) and ``wgpuviewer.relief`` (auto
measures its table with the probe); never another technique folder.
"""

from __future__ import annotations

import importlib
import os
import pkgutil
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

from wgpuviewer.core.discovered import Discovered
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.params import Fixed, Param, Parametrized

if TYPE_CHECKING:
    from wgpuviewer.core.slots import MapSlot

#: TraceParams fields every technique has, with their WGSL types: the material's relief scale, its depth map's size
#: in texels (for the mip level) and depth range (maps.depth_range: the layer searches march only that range,
#: common/trace.wgsl's relief_range). The technique's parameters and fixed values follow.
COMMON_TRACE_FIELDS = (("height_scale", "f32"), ("depth_width", "u32"), ("depth_height", "u32"), ("depth_min", "f32"),
                       ("depth_max", "f32"))

#: Full heat of the cost view for techniques without a layer bound (fetches per pixel).
COMMON_COST_SCALE = 64.0

#: Hard cap on any layer count (generated into every technique's WGSL as ``MAX_LAYERS``).
MAX_LAYERS = 1024


@dataclass(frozen=True)
class Technique(Parametrized):
    name: str  # also its folder's name
    key: str  # default keyboard key in the viewer
    description: str
    cost: str  # what it costs, for humans (README table, `wgpuviewer techniques`)
    textures: tuple[str, ...]  # slot names: 'albedo', 'normal', 'depth', the derived maps and its own ``slots``
    params: tuple[Param, ...] = ()
    ray_search: bool = False
    #: Its place in the registry's order (the first is the scenes' default; the viewer's keys, the README table, the
    #: benchmark follow it): by this number, then by name. The shipped ones are 10 apart, so a new one fits anywhere.
    order: int = field(kw_only=True)
    #: Texture slots only this technique uses (e.g. auto's table); ``relief.maps`` collects every technique's.
    slots: tuple[MapSlot, ...] = ()
    #: Its folder (discovery fills it in from where ``TECHNIQUE`` was found).
    folder: str = ""
    #: The WGSL file: NAME.wgsl in its folder by default; another technique's, relative to this folder
    #: (distance_refined: ``../distance/distance.wgsl``); or an absolute path.
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
    #: Lines the viewer's info panel shows under the technique, given the scene's materials (name -> material) and
    #: the parameters (auto: what it chooses per view-angle range on each material); None: none.
    panel_lines: Callable[[dict, dict], list[str]] | None = None
    #: Code paths of its WGSL a material's draw may leave out (auto: its candidates' methods): each NAME gets a
    #: generated ``const USES_NAME: bool`` (``relief.shaders``), true unless the draw's material variant leaves it out,
    #: and its WGSL runs the path only under it, so the compiler drops the paths a material does not take.
    code_paths: tuple[str, ...] = ()
    #: Which ``code_paths`` drawing a material (a scene material) with parameters ``params`` runs; the renderer
    #: compiles a module per distinct answer (``MaterialVariant.paths``). None: every path, always.
    paths_used: Callable[[object, dict], tuple[str, ...]] | None = None

    @property
    def wgsl_file(self) -> str:
        """The file for the WGSL composer: an absolute path (its ``// #include`` lines resolve against wgsl/)."""
        return os.path.normpath(Path(self.folder, self.wgsl or f"{self.name}.wgsl"))

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


def discover() -> dict[str, Technique]:
    """Every technique folder on this package's search path (``__path__``), imported, by ``Technique.order`` then
    name: a subpackage NAME whose ``TECHNIQUE`` is named NAME, with its folder filled in."""
    found = []
    for info in pkgutil.iter_modules(__path__):
        if not info.ispkg:
            continue  # shared: what several folders use
        module = importlib.import_module(f"{__name__}.{info.name}")
        entry = getattr(module, "TECHNIQUE", None)
        if not isinstance(entry, Technique) or entry.name != info.name:
            raise ValueError(f"technique folder {module.__file__}: expected TECHNIQUE, a Technique named {info.name!r}")
        found.append(replace(entry, folder=str(Path(module.__file__).parent)))
    return {t.name: t for t in sorted(found, key=lambda t: (t.order, t.name))}


#: The discovered techniques by name, in order: read-only, discovered on first use (and again when the package's
#: search path changes: a test adds a throw-away folder that way).
TECHNIQUES: Mapping[str, Technique] = Discovered("TECHNIQUES", discover, lambda: tuple(__path__))


def get_technique(name: str, where: str = "technique") -> Technique:
    try:
        return TECHNIQUES[name]
    except KeyError:
        raise UserError(f"{where} = {name!r}: unknown technique; expected one of {', '.join(TECHNIQUES)}") from None


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
