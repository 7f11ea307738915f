"""pom_adaptive: the thesis' adaptive POM, its layer count from the view angle and the complexity map
(``pom_adaptive.wgsl``).

May import: ``wgpuviewer.core`` and the registry (``wgpuviewer.techniques``, ``shared``).
"""

from wgpuviewer.core.params import Param
from wgpuviewer.techniques import MAX_LAYERS, Technique

TECHNIQUE = Technique(
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
    ray_search=True, order=60, fetch_bound=lambda p: max(p["min_layers"], p["max_layers"]) + 1,
    cost_view_scale=lambda p: p["max_layers"] + 1.0,
    layers_view_range=lambda p: (float(p["min_layers"]), float(p["max_layers"])),
    contract_params=({"angle_only": True}, {"min_layers": 8, "max_layers": 2}),
    accuracy_settings=({}, {"angle_only": True}),
)
