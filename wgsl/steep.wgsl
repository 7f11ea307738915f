// Steep parallax mapping (thesis listing): the layer march of prelude.wgsl, stopping at the first layer
// below the surface.
fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let n = layer_count();
    let m = layer_march(uv0, v, lod, n);
    return TraceResult(m.uv, f32(m.layers) * m.layer_step, fetch_count, is_grazing(v), n);
}
