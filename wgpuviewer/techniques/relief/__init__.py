"""relief: Policarpo's relief mapping, a linear search then a binary one ended by a secant (``relief.wgsl``).

May import: ``wgpuviewer.core`` and the registry (``wgpuviewer.techniques``, ``shared``).
"""

from wgpuviewer.core.params import Param
from wgpuviewer.techniques import MAX_LAYERS, Technique
from wgpuviewer.techniques.shared import RELIEF_BINARY_STEPS_MAX

TECHNIQUE = Technique(
    "relief", "7",
    "Relief mapping (Policarpo): linear search in equal depth steps, then binary search between the last "
    "step above the surface and the first below it, ended by the secant through the final bracket's ends "
    "(no extra fetch; with 0 binary steps this is POM).",
    "up to linear_steps+1+binary_steps depth fetches", ("albedo", "normal", "depth"),
    (
        Param("linear_steps", 16, 1, MAX_LAYERS, int, "linear search steps (depth layers)"),
        Param("binary_steps", 6, 0, RELIEF_BINARY_STEPS_MAX, int, "binary refinement steps (each halves the bracket)"),
    ),
    ray_search=True, order=70, fetch_bound=lambda p: p["linear_steps"] + 1 + p["binary_steps"],
    cost_view_scale=lambda p: p["linear_steps"] + 1.0 + p["binary_steps"],
    layers_view_range=lambda p: (0.0, float(p["linear_steps"])),
    contract_params=({"linear_steps": 1, "binary_steps": 0},),
    accuracy_settings=({}, {"linear_steps": 32, "binary_steps": 8}),
)
