"""parallax: parallax (offset) mapping, one depth fetch, with Welsh's offset limiting as a flag (``parallax.wgsl``).

May import: ``wgpuviewer.core`` and the registry (``wgpuviewer.techniques``, ``shared``).
"""

from wgpuviewer.core.params import Param
from wgpuviewer.techniques import Technique, common_cost_scale, no_layers

TECHNIQUE = Technique(
    "parallax", "3",
    "Parallax (offset) mapping: uv' = uv - V.xy/V.z * depth(uv) * scale; with offset limiting "
    "the division by V.z is dropped (Welsh), which bounds the offset at grazing angles.",
    "1 depth fetch", ("albedo", "normal", "depth"),
    (Param("offset_limiting", False, 0, 1, bool, "drop the 1/V.z factor (bounded offset)"),),
    ray_search=True, order=30, fetch_bound=lambda p: 1, cost_view_scale=common_cost_scale,
    layers_view_range=no_layers, contract_params=({"offset_limiting": True},),
    accuracy_settings=({}, {"offset_limiting": True}),
)
