"""What several technique folders share (a folder never imports another, so it lives here, beside the registry):
the layer-search entry of steep and pom; the distance tracer's fixed values, cost and bound (distance and
distance_refined run one WGSL file); the grazing finish of distance, distance_refined and cone; and the defaults one
technique's parameters take that another runs with (quadmax's steps and top offset, relief's binary-step cap: auto's
candidates and quadmax_pom use them).

May import: ``wgpuviewer.core`` and the registry (``wgpuviewer.techniques``) only.
"""

from __future__ import annotations

import math

from wgpuviewer.core.params import Fixed, Param
from wgpuviewer.techniques import MAX_LAYERS, Technique

#: quadmax's default step cap (auto's quadmax candidate runs with it too).
QUADMAX_STEPS = 1024
#: quadmax's default start-level offset (quadmax_pom's skip uses it too).
QUADMAX_TOP_OFFSET = -2
#: relief's cap on binary steps (its parameter's range; auto clamps the table's count to it).
RELIEF_BINARY_STEPS_MAX = 32

#: The grazing finish of distance and cone (common/maxmip_walk.wgsl): after this many slow steps (slow_step there) a
#: ray goes on with the max-pyramid walk, for at most PYRAMID_STEPS steps (four times maxmip's default cap: at 89.9
#: degrees a ray on the 256x256 bricks map needs more than 1024).
HANDOVER_STEPS = 8
PYRAMID_STEPS = 4096
#: The TraceParams values of the grazing finish (distance and cone).
GRAZING_FINISH = (Fixed("handover_steps", HANDOVER_STEPS, "u32"), Fixed("pyramid_steps", PYRAMID_STEPS, "u32"))


def layer_search(name: str, key: str, order: int, description: str, accuracy_settings: tuple[dict, ...]) -> Technique:
    """steep and pom: the same layer march with the same parameter, bound and coverage (their WGSL differs in the
    finish)."""
    return Technique(
        name, key, description, "up to N+1 depth fetches", ("albedo", "normal", "depth"),
        (Param("layers", 16, 1, MAX_LAYERS, int, "layer count: the ray is tested at this many evenly spaced depths"),),
        ray_search=True, order=order, fetch_bound=lambda p: p["layers"] + 1,
        cost_view_scale=lambda p: p["layers"] + 1.0, layers_view_range=lambda p: (0.0, float(p["layers"])),
        contract_params=({"layers": 1},), accuracy_settings=accuracy_settings,
    )


def distance_fixed(sectors: int, bands: int, max_angle: float | None) -> tuple[Fixed, ...]:
    """TraceParams values of distance.wgsl for a texture of ``sectors`` x ``bands`` direction volumes plus the plain
    one (max_angle = None: the plain map alone, one volume every ray reads; steep_cos -2: no ray is steeper)."""
    if max_angle is None:
        sectors, bands, steep_cos, volumes = 1, 1, -2.0, 1
    else:
        steep_cos, volumes = math.cos(math.radians(max_angle)), sectors * bands + 1
    return (Fixed("sectors", sectors, "u32"), Fixed("bands", bands, "u32"), Fixed("steep_cos", steep_cos, "f32"),
            Fixed("volumes", volumes, "u32"))


DISTANCE_COST = (f"one volume fetch per step + one 2x2 gather per exact cell; a grazing ray's pyramid walk up to "
                 f"{PYRAMID_STEPS}")


def distance_fetch_bound(p: dict) -> int:
    return 2 * p["iterations"] + PYRAMID_STEPS
