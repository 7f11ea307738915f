// Maximum-mipmap tracing (Romanyuk & Dudnyk 2018, modified MIP pyramid), exact on the bilinear surface: the
// pyramid walk of common/maxmip_walk.wgsl from the map's shallowest depth (above it the ray meets nothing:
// relief_range, common/trace.wgsl). At level 0 the cell's exact quadratic is solved, so the first hit matches
// wgpuviewer/reference.py to float32 precision, thin walls and spikes included. Bounded by max_steps (capped rays
// are flagged).
// #include "common/maxmip_walk.wgsl"

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    return maxmip_walk(uv0, v, relief_range(0.0).x, clamp(trace_params.max_steps, MAX_STEPS_MIN, MAX_STEPS_MAX));
}
