"""distance_refined: the distance tracer on the direction-binned refined map (Romanyuk et al. 2017). No WGSL of its
own: it runs distance's file (``../distance/distance.wgsl``) with the map's bins as fixed values; the bins are the
map kind's options (``maptools.kinds.distance_refined.slot``).

May import: ``wgpuviewer.core``, the registry (``wgpuviewer.techniques``, ``shared``) and its map kind.
"""

from maptools.kinds.distance_refined.slot import REFINED_BANDS, REFINED_MAX_ANGLE, REFINED_SECTORS
from wgpuviewer.core.params import Param
from wgpuviewer.techniques import Technique, common_cost_scale, no_layers
from wgpuviewer.techniques.shared import DISTANCE_COST, GRAZING_FINISH, distance_fetch_bound, distance_fixed

TECHNIQUE = Technique(
    "distance_refined", "0",
    "Distance-map parallax on the direction-binned refined map (Romanyuk et al. 2017): the same tracer as distance "
    f"(distance.wgsl); the map has one volume per bin of ray directions ({REFINED_SECTORS} azimuth sectors x "
    f"{REFINED_BANDS} polar bands within {REFINED_MAX_ANGLE:g} degrees) with longer safe steps for "
    "the rays of that bin, and the plain volume for steeper rays. A ray picks its volume once.",
    DISTANCE_COST, ("albedo", "normal", "depth", "distance_refined", "maxmip"),
    (Param("iterations", 256, 1, 4096, int, "cap on steps (sphere steps + exact cells); capped rays flagged"),),
    ray_search=True, order=100, wgsl="../distance/distance.wgsl", fetch_bound=distance_fetch_bound, exact=True,
    fixed=distance_fixed(REFINED_SECTORS, REFINED_BANDS, REFINED_MAX_ANGLE) + GRAZING_FINISH,
    cost_view_scale=common_cost_scale, layers_view_range=no_layers,
    contract_params=({"iterations": 8},), accuracy_settings=({},),
)
