// Parallax occlusion mapping: the steep-parallax layer search, then the crossing point by linear
// interpolation between the last layer above the surface and the first one below it
// (pom_search in common/layer_march.wgsl, shared with pom_adaptive).
// #include "common/layer_march.wgsl"

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    return pom_search(uv0, v, lod, 0.0, clamp(trace_params.layers, LAYERS_MIN, LAYERS_MAX));
}
