// #include "common/depth.wgsl"

// The steep-parallax loop: step through n equal depth layers of the relief's range from t0 on (relief_range,
// common/trace.wgsl: t0 = 0 for the whole relief; the quadmax_pom hybrid starts lower) until the first layer below
// the surface. Bounded by n <= MAX_LAYERS: at layer n the ray is at the map's deepest depth, on or below the
// surface, so the thesis' open-ended while loop always ends there anyway.
struct LayerMarch {
    uv: vec2f,          // where the march stopped
    duv: vec2f,         // uv step per layer
    layers: u32,        // layers stepped (0: the entry point is already on the surface)
    t_start: f32,       // depth of layer 0
    layer_step: f32,    // depth per layer: (end - t_start) / n
    d: f32,             // depth at uv
    d_prev: f32,        // depth one layer earlier (kept instead of fetched again)
}

fn layer_march(uv0: vec2f, v: vec3f, lod: f32, t0: f32, n: u32) -> LayerMarch {
    let range = relief_range(t0);
    let t_start = range.x;
    let layer_step = (range.y - t_start) / f32(n);
    let span = parallax_span(v);
    let duv = span * layer_step;
    var uv = uv0 - span * t_start;
    var d = depth_at(uv, lod);
    var d_prev = d;
    var i = 0u;
    while i < n && t_start + f32(i) * layer_step < d {
        i += 1u;
        uv -= duv;
        d_prev = d;
        d = depth_at(uv, lod);
    }
    return LayerMarch(uv, duv, i, t_start, layer_step, d, d_prev);
}

// The POM search shared by pom, pom_adaptive, auto and quadmax_pom: the layer march from t0 on, then linear
// interpolation between the last layer above the surface and the first one below it (the thesis fetches the
// previous sample twice; the march keeps it).
fn pom_search(uv0: vec2f, v: vec3f, lod: f32, t0: f32, n: u32) -> TraceResult {
    let m = layer_march(uv0, v, lod, t0, n);
    if m.layers == 0u {
        return TraceResult(m.uv, m.t_start, fetch_count, is_grazing(v), n);
    }
    let layer = m.t_start + f32(m.layers) * m.layer_step;
    let after = m.d - layer;                            // <= 0: this sample is below the surface
    let before = m.d_prev - (layer - m.layer_step);     // > 0: the previous one was above it
    let denom = after - before;
    // denom < 0 whenever the bracket is real; guard the degenerate case instead of dividing by 0.
    let w = select(0.0, clamp(after / denom, 0.0, 1.0), denom < -1e-12);
    return TraceResult(m.uv + m.duv * w, layer - w * m.layer_step, fetch_count, is_grazing(v), n);
}
