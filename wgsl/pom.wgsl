// Parallax occlusion mapping: the steep-parallax layer search, then the crossing point by linear
// interpolation between the last layer above the surface and the first one below it.
// The previous sample is kept instead of fetched again (the thesis fetches it twice).
fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let n = layer_count();
    let layer_step = 1.0 / f32(n);
    let duv = parallax_span(v) * layer_step;
    var uv = uv0;
    var d = depth_at(uv, lod);
    var d_prev = d;
    var i = 0u;
    while i < n && f32(i) * layer_step < d {
        i += 1u;
        uv -= duv;
        d_prev = d;
        d = depth_at(uv, lod);
    }
    if i == 0u {
        return TraceResult(uv0, 0.0, fetch_count, is_grazing(v));
    }
    let layer = f32(i) * layer_step;
    let after = d - layer;                          // <= 0: this sample is below the surface
    let before = d_prev - (layer - layer_step);     // > 0: the previous one was above it
    let denom = after - before;
    // denom < 0 whenever the bracket is real; guard the degenerate case instead of dividing by 0.
    let w = select(0.0, clamp(after / denom, 0.0, 1.0), denom < -1e-12);
    return TraceResult(uv + duv * w, layer - w * layer_step, fetch_count, is_grazing(v));
}
