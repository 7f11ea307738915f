"""distance: distance-map parallax (Donnelly) on the plain distance volume (``distance.wgsl``, which
distance_refined runs too; the shared fixed values, cost and bound are in ``shared``).

May import: ``wgpuviewer.core`` and the registry (``wgpuviewer.techniques``, ``shared``).
"""

from wgpuviewer.core.params import Param
from wgpuviewer.techniques import Technique, common_cost_scale, no_layers
from wgpuviewer.techniques.shared import DISTANCE_COST, GRAZING_FINISH, distance_fetch_bound, distance_fixed

TECHNIQUE = Technique(
    "distance", "9",
    "Distance-map parallax (Donnelly): sphere tracing through a 3D map of safe radii (box-exact distance to a "
    "sub-cell outer solid); where the radius does not leave the current bilinear cell the cell is solved "
    "exactly and skipped if it holds no hit. A grazing ray finishes with maxmip's pyramid walk. Never passes a "
    "surface.",
    DISTANCE_COST, ("albedo", "normal", "depth", "distance", "maxmip"),
    (Param("iterations", 256, 1, 4096, int, "cap on steps (sphere steps + exact cells); capped rays flagged"),),
    ray_search=True, order=90, fixed=distance_fixed(1, 1, None) + GRAZING_FINISH, fetch_bound=distance_fetch_bound,
    exact=True,
    cost_view_scale=common_cost_scale, layers_view_range=no_layers,
    contract_params=({"iterations": 8},), accuracy_settings=({},),
)
