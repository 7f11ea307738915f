"""quadmax: max-quadtree tracing with packed 2x2-cell leaves (``quadmax.wgsl``). Its default step cap and top
offset are in ``shared`` (auto's candidate and quadmax_pom run with them).

May import: ``wgpuviewer.core`` and the registry (``wgpuviewer.techniques``, ``shared``).
"""

from wgpuviewer.core.params import Param
from wgpuviewer.techniques import Technique, common_cost_scale, no_layers
from wgpuviewer.techniques.shared import QUADMAX_STEPS, QUADMAX_TOP_OFFSET

TECHNIQUE = Technique(
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
    ray_search=True, order=110, fetch_bound=lambda p: 2 * p["max_steps"],
    cost_view_scale=common_cost_scale, layers_view_range=no_layers,
    contract_params=({"top_offset": 3, "max_steps": 8}, {"top_offset": -8}), accuracy_settings=({},),
)
