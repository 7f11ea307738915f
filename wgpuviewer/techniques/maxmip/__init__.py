"""maxmip: maximum-mipmap tracing on the max pyramid, exact on the bilinear surface (``maxmip.wgsl``).

May import: ``wgpuviewer.core`` and the registry (``wgpuviewer.techniques``, ``shared``).
"""

from wgpuviewer.core.params import Param
from wgpuviewer.techniques import Technique, common_cost_scale, no_layers

TECHNIQUE = Technique(
    "maxmip", "8",
    "Maximum-mipmap tracing (Romanyuk & Dudnyk 2018, modified MIP pyramid): descend a max pyramid over the "
    "bilinear cells from the top, skip nodes the ray passes above, climb back after a skip; solve the exact "
    "per-cell quadratic at the base. Finds the first hit of the bilinear surface to float32 precision (repeat "
    "addressing).",
    "pyramid texel per node + one 2x2 gather per base cell", ("albedo", "normal", "depth", "maxmip"),
    (Param("max_steps", 1024, 1, 65536, int, "cap on traversal steps (capped rays are flagged)"),),
    ray_search=True, order=80, fetch_bound=lambda p: p["max_steps"], exact=True,
    cost_view_scale=common_cost_scale, layers_view_range=no_layers,
    contract_params=({"max_steps": 8},), accuracy_settings=({},),
)
