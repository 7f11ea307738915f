// Parallax (offset) mapping: one depth fetch, uv' = uv - V.xy / V.z * depth(uv) * scale.
// Offset limiting (Welsh) drops the 1/V.z factor, which bounds the offset at grazing angles.
// #include "common/depth.wgsl"

fn trace(uv: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let d = depth_at(uv, lod);
    let limited = trace_params.offset_limiting > 0.5;
    var offset = parallax_span(v) * d;
    if limited {
        offset = v.xy * (d * trace_params.height_scale);
    }
    return TraceResult(uv - offset, d, fetch_count, is_grazing(v) && !limited, 0u);
}
