// Relief mapping (Policarpo et al.): a linear search in equal depth steps of the map's depth range
// (relief_range, common/trace.wgsl) finds the first step below the surface, then a binary search halves the
// bracket [last step above, first step below] binary_steps times. Returns the shallowest point confirmed below the surface (with 0 binary steps
// this is exactly steep parallax). Positions are computed from uv0 (no accumulated drift).
// Bounded: at most linear_steps + 1 + binary_steps fetches.
// #include "common/binary.wgsl"

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let n = clamp(trace_params.linear_steps, LINEAR_STEPS_MIN, LINEAR_STEPS_MAX);
    let range = relief_range(0.0);  // the map's depth range: no step outside it can meet the surface
    let step = (range.y - range.x) / f32(n);
    let span = parallax_span(v);
    var d = depth_at(uv0 - span * range.x, lod);
    var i = 0u;
    while i < n && range.x + f32(i) * step < d {
        i += 1u;
        d = depth_at(uv0 - span * (range.x + f32(i) * step), lod);
    }
    if i == 0u {
        return TraceResult(uv0 - span * range.x, range.x, fetch_count, is_grazing(v), n);
    }
    // The bracket: the last step above the surface, the first one below (or on) it.
    let nb = clamp(trace_params.binary_steps, BINARY_STEPS_MIN, BINARY_STEPS_MAX);
    let below = range.x + f32(i) * step;
    let hi = binary_refine(uv0, span, below - step, below, nb, lod).y;
    return TraceResult(uv0 - span * hi, hi, fetch_count, is_grazing(v), n);
}
