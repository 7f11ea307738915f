"""quadmax_pom: quadmax's exact walk cut short, then a POM finish (``quadmax_pom.wgsl``).

May import: ``wgpuviewer.core`` and the registry (``wgpuviewer.techniques``, ``shared``).
"""

from wgpuviewer.core.params import Fixed, Param
from wgpuviewer.techniques import MAX_LAYERS, Technique
from wgpuviewer.techniques.shared import QUADMAX_TOP_OFFSET

TECHNIQUE = Technique(
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
    ray_search=True, order=120, fixed=(Fixed("top_offset", QUADMAX_TOP_OFFSET, "i32"),),
    fetch_bound=lambda p: 2 * p["skip_steps"] + p["layers"] + 1,
    cost_view_scale=lambda p: p["layers"] + 1.0, layers_view_range=lambda p: (0.0, float(p["layers"])),
    contract_params=({"skip_steps": 1, "layers": 1},), accuracy_settings=({}, {"skip_steps": 16}),
)
