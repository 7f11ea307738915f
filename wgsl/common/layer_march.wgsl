// #include "common/depth.wgsl"

// The steep-parallax loop: step through n equal depth layers of [t0, 1] (t0 = 0: the whole relief; the
// quadmax_pom hybrid starts lower) until the first layer below the surface.
// Bounded by n <= MAX_LAYERS: at layer n the ray is at t = 1, below any depth, so the thesis' open-ended
// while loop always ends there anyway.
struct LayerMarch {
    uv: vec2f,          // where the march stopped
    duv: vec2f,         // uv step per layer
    layers: u32,        // layers stepped (0: the entry point is already on the surface)
    layer_step: f32,    // (1 - t0) / n
    d: f32,             // depth at uv
    d_prev: f32,        // depth one layer earlier (kept instead of fetched again)
}

fn layer_march(uv0: vec2f, v: vec3f, lod: f32, t0: f32, n: u32) -> LayerMarch {
    let layer_step = (1.0 - t0) / f32(n);
    let span = parallax_span(v);
    let duv = span * layer_step;
    var uv = uv0 - span * t0;
    var d = depth_at(uv, lod);
    var d_prev = d;
    var i = 0u;
    while i < n && t0 + f32(i) * layer_step < d {
        i += 1u;
        uv -= duv;
        d_prev = d;
        d = depth_at(uv, lod);
    }
    return LayerMarch(uv, duv, i, layer_step, d, d_prev);
}

// The POM search shared by pom, pom_adaptive, auto and quadmax_pom: the layer march over [t0, 1], then linear
// interpolation between the last layer above the surface and the first one below it (the thesis fetches the
// previous sample twice; the march keeps it).
fn pom_search(uv0: vec2f, v: vec3f, lod: f32, t0: f32, n: u32) -> TraceResult {
    let m = layer_march(uv0, v, lod, t0, n);
    if m.layers == 0u {
        return TraceResult(m.uv, t0, fetch_count, is_grazing(v), n);
    }
    let layer = t0 + f32(m.layers) * m.layer_step;
    let after = m.d - layer;                            // <= 0: this sample is below the surface
    let before = m.d_prev - (layer - m.layer_step);     // > 0: the previous one was above it
    let denom = after - before;
    // denom < 0 whenever the bracket is real; guard the degenerate case instead of dividing by 0.
    let w = select(0.0, clamp(after / denom, 0.0, 1.0), denom < -1e-12);
    return TraceResult(m.uv + m.duv * w, layer - w * m.layer_step, fetch_count, is_grazing(v), n);
}
