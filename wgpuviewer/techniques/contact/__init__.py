"""contact: contact-refinement parallax, a linear search then a second linear search inside the bracket it found,
ended by relief's secant (``contact.wgsl``).

May import: ``wgpuviewer.core`` and the registry (``wgpuviewer.techniques``, ``shared``).
"""

from wgpuviewer.core.params import Param
from wgpuviewer.techniques import MAX_LAYERS, Technique

#: The most sub-steps of the second search (each one fetch; past 64 a binary search of the bracket is cheaper).
REFINE_STEPS_MAX = 64

TECHNIQUE = Technique(
    "contact", "-",
    "Contact-refinement parallax: linear search in equal depth steps, then a second linear search in "
    "refine_steps equal sub-steps of the bracket [last step above the surface, first step below], ended by the "
    "secant through the final sub-bracket's ends (no extra fetch; with 1 refine step this is POM).",
    "up to linear_steps+refine_steps depth fetches", ("albedo", "normal", "depth"),
    (
        Param("linear_steps", 16, 1, MAX_LAYERS, int, "linear search steps (depth layers)"),
        Param("refine_steps", 8, 1, REFINE_STEPS_MAX, int, "sub-steps of the second linear search in the bracket"),
    ),
    ray_search=True, order=75, fetch_bound=lambda p: p["linear_steps"] + p["refine_steps"],
    cost_view_scale=lambda p: p["linear_steps"] + float(p["refine_steps"]),
    layers_view_range=lambda p: (0.0, float(p["linear_steps"])),
    contract_params=({"linear_steps": 1, "refine_steps": 1}, {"linear_steps": 4, "refine_steps": REFINE_STEPS_MAX}),
    accuracy_settings=({}, {"linear_steps": 8, "refine_steps": 8}, {"linear_steps": 32, "refine_steps": 8}),
)
