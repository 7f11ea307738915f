// Parallax (offset) mapping: one depth fetch (parallax_offset, common/parallax.wgsl, shared with auto).
// #include "common/parallax.wgsl"

fn trace(uv: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    return parallax_offset(uv, v, lod, trace_params.offset_limiting != 0u);
}
