// Derivative source `displaced` (Romanyuk & Dudnyk 2017 (filtering with parallax mapping), formula 3): screen-space
// differences of the traced hit uv, so the footprint follows the displaced texture coordinates. Where neighbouring
// pixels hit different surfaces (depth discontinuities) the differences jump by the parallax offset; each is
// bounded to DERIVATIVE_LIMIT times the unperturbed one (flagged bounded; the raw ratio is reported). Called in
// uniform control flow.
// #include "common/footprint.wgsl"

fn texture_derivatives(uv0: vec2f, v: vec3f, hit: TraceResult) -> Derivatives {
    return bounded_derivatives(dpdx(hit.uv), dpdy(hit.uv), dpdx(uv0), dpdy(uv0));
}
