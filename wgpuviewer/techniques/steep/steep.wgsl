// Steep parallax mapping (thesis listing): the layer march of common/layer_march.wgsl, stopping at the first layer
// below the surface.
// #include "common/layer_march.wgsl"

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let n = clamp(trace_params.layers, LAYERS_MIN, LAYERS_MAX);
    let m = layer_march(uv0, v, lod, 0.0, n);
    return TraceResult(m.uv, m.t_start + f32(m.layers) * m.layer_step, fetch_count, is_grazing(v), n);
}
