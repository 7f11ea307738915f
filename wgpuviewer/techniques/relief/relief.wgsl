// Relief mapping (Policarpo et al.): a linear search in equal depth steps of the map's depth range (relief_range,
// common/trace.wgsl) finds the first step below the surface, a binary search halves the bracket [last step above,
// first step below] binary_steps times, and the secant through the final bracket's ends gives the hit
// (relief_search in common/binary.wgsl, shared with auto). With 0 binary steps this is POM.
// Bounded: at most linear_steps + 1 + binary_steps fetches.
// #include "common/binary.wgsl"

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let n = clamp(trace_params.linear_steps, LINEAR_STEPS_MIN, LINEAR_STEPS_MAX);
    let nb = clamp(trace_params.binary_steps, BINARY_STEPS_MIN, BINARY_STEPS_MAX);
    return relief_search(uv0, v, lod, n, nb);
}
