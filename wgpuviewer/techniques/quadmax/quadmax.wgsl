// Max-quadtree tracing with packed 2x2-cell leaves (common/quadmax.wgsl): never behind the first hit, one
// fetch per leaf and per quad texel read.
// #include "common/quadmax.wgsl"

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let top_offset = clamp(trace_params.top_offset, TOP_OFFSET_MIN, TOP_OFFSET_MAX);
    return quadmax_search(uv0, v, top_offset, clamp(trace_params.max_steps, MAX_STEPS_MIN, MAX_STEPS_MAX));
}
