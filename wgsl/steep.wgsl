// Steep parallax mapping (thesis listing): step through N equal depth layers and stop at the first
// layer below the surface. The loop is bounded by N <= MAX_LAYERS: at layer N the ray is at t = 1,
// below any depth, so the listing's open-ended while loop always ends there anyway.
fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let n = layer_count();
    let layer_step = 1.0 / f32(n);
    let duv = parallax_span(v) * layer_step;
    var uv = uv0;
    var d = depth_at(uv, lod);
    var i = 0u;
    while i < n && f32(i) * layer_step < d {
        i += 1u;
        uv -= duv;
        d = depth_at(uv, lod);
    }
    return TraceResult(uv, f32(i) * layer_step, fetch_count, is_grazing(v), n);
}
