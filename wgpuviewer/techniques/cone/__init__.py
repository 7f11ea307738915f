"""cone: robust relaxed cone stepping, exact on the bilinear surface (``cone.wgsl``). Its bracket finish's constants
live here; the cone map's options (widest cone, lookup) are the map kind's (``maptools.kinds.cone.slot``).

May import: ``wgpuviewer.core``, the registry (``wgpuviewer.techniques``, ``shared``) and its map kind.
"""

from maptools.kinds.cone.slot import CONE_MAX_RATIO
from wgpuviewer.core.params import Fixed, Param
from wgpuviewer.techniques import Technique, common_cost_scale, no_layers
from wgpuviewer.techniques.shared import GRAZING_FINISH, PYRAMID_STEPS

#: cone.wgsl's bracket finish: halvings that bring a bracket to one cell (24: float32 t cannot be split further
#: anyway; a longer bracket ends flagged at its free end), and the cells a one-cell bracket crosses (one x and one
#: y border) plus the cell its start may round into.
CONE_HALVINGS_MAX = 24
CONE_FINISH_CELLS = 4

TECHNIQUE = Technique(
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
    ray_search=True, order=140, exact=True,
    fixed=(Fixed("max_ratio", CONE_MAX_RATIO, "f32"), Fixed("halvings_max", CONE_HALVINGS_MAX, "u32"),
           Fixed("finish_cells", CONE_FINISH_CELLS, "u32"), *GRAZING_FINISH),
    fetch_bound=lambda p: 2 * p["iterations"] + CONE_HALVINGS_MAX + CONE_FINISH_CELLS + PYRAMID_STEPS,
    cost_view_scale=common_cost_scale, layers_view_range=no_layers,
    contract_params=({"iterations": 8},), accuracy_settings=({},),
)
