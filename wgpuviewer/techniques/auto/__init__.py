"""auto: the error budget as a technique (``auto.wgsl``): per pixel the view angle picks the cheapest candidate
that met the budget on the material's own height map. Its table (``autotable``: candidates, bins, budgets, the
measurement with the probe) and its own texture slot (``slot``: ``auto_table``) live here.

May import: ``wgpuviewer.core``, the registry (``wgpuviewer.techniques``, ``shared``), ``maptools`` and
``wgpuviewer.relief`` (the probe and the float64 reference measure the table).
"""

from wgpuviewer.core.params import Fixed, Param, resolve_params
from wgpuviewer.techniques import TECHNIQUES, Technique, common_cost_scale
from wgpuviewer.techniques.shared import QUADMAX_STEPS, RELIEF_BINARY_STEPS_MAX

from .autotable import (
    AUTO_BINS_PER_OCTAVE,
    AUTO_BUDGET_LEVELS,
    AUTO_BUDGET_LOG2_MIN,
    AUTO_CANDIDATES,
    AUTO_METHODS,
    AUTO_TAN0,
    MAX_ERROR_PX,
    panel_lines,
    paths_used,
)
from .slot import AUTO_TABLE_SLOT


def fetch_bound(params: dict) -> int:
    """The largest bound of the ray-search candidates, each at its own parameters."""
    return max(TECHNIQUES[name].fetch_bound(resolve_params(TECHNIQUES[name], overrides))
               for name, overrides in AUTO_CANDIDATES if TECHNIQUES[name].ray_search)


TECHNIQUE = Technique(
    "auto", "-",
    "The error budget as a technique: per pixel, the view angle picks the cheapest candidate (basic, "
    "parallax, POM 4-64 layers, relief 4-32 linear steps with 1 or 2 binary steps, quadmax) whose p97.5 UV "
    "error the probe measured within max_error on this material's own height map, at both ends of the "
    "angle bin (techniques/auto/autotable.py; cached with the maps). With max_error_px > 0 the budget grows "
    "with the texels a pixel spans along the ray.",
    "the chosen candidate's fetches (one table texel, not counted)",
    ("albedo", "normal", "depth", "quadmax", "auto_table"),
    (Param("max_error", 0.5, 2.0 ** AUTO_BUDGET_LOG2_MIN, 2.0 ** (AUTO_BUDGET_LOG2_MIN + AUTO_BUDGET_LEVELS - 1),
           float, "UV error budget in texels (the table's budgets are powers of 2: the largest one not "
           "above this is used)"),
     Param("max_error_px", 0.0, 0.0, MAX_ERROR_PX, float, "screen-space budget in pixels (0: off): where a "
           "pixel spans more than max_error / max_error_px texels along the ray, the texels it spans set the budget "
           "(auto.wgsl auto_budget), so distant and minified surfaces run cheaper; magnified ones keep max_error")),
    ray_search=True, order=130, slots=(AUTO_TABLE_SLOT,), panel_lines=panel_lines,
    code_paths=tuple(AUTO_METHODS), paths_used=paths_used,
    fixed=(Fixed("bin_tan0", AUTO_TAN0, "f32"), Fixed("bins_per_octave", AUTO_BINS_PER_OCTAVE, "u32"),
           Fixed("budget_log2_min", AUTO_BUDGET_LOG2_MIN, "i32"), Fixed("quadmax_steps", QUADMAX_STEPS, "u32"),
           Fixed("binary_steps_max", RELIEF_BINARY_STEPS_MAX, "u32")),
    fetch_bound=fetch_bound,
    cost_view_scale=common_cost_scale,
    # the layers view shows the chosen candidate (1-based, cheapest first) instead of a layer count
    layers_view_range=lambda p: (1.0, float(len(AUTO_CANDIDATES))),
    contract_params=({"max_error": 2.0 ** AUTO_BUDGET_LOG2_MIN},
                     {"max_error": 2.0 ** (AUTO_BUDGET_LOG2_MIN + AUTO_BUDGET_LEVELS - 1)}, {"max_error_px": 0.5}),
    accuracy_settings=({"max_error": 0.25}, {"max_error": 0.5}, {"max_error": 1.0}),
)
