// Parallax (offset) mapping (the parallax technique; auto uses it at shallow views): one depth fetch,
// uv' = uv - V.xy / V.z * depth(uv) * scale. Offset limiting (Welsh) drops the 1/V.z factor, which bounds the
// offset at grazing angles. Either way a grazing, horizontal or back-facing view (is_grazing) is flagged, as by every
// technique: its offset is finite but says nothing about where such a ray meets the relief.
// #include "common/depth.wgsl"

fn parallax_offset(uv: vec2f, v: vec3f, lod: f32, limited: bool) -> TraceResult {
    let d = depth_at(uv, lod);
    var offset = parallax_span(v) * d;
    if limited {
        offset = v.xy * (d * trace_params.height_scale);
    }
    return TraceResult(uv - offset, d, fetch_count, is_grazing(v), 0u);
}
