// Adaptive parallax occlusion mapping (thesis, section 2): the layer count follows the view angle and
// the complexity map, then the POM search runs with that many layers (pom_search, common/layer_march.wgsl).
//   F = (1 - |V.N|)^0.8, NTmin = mix(Nmin, Nmax/2, F), NTmax = mix(Nmin, Nmax, F),
//   N = int(mix(NTmin, NTmax, C))   -- truncation toward zero, as the thesis' int()
// C is read once at the entry uv with an explicit level (bilinear, level 0), before the loop, so the
// uniformity rule holds. angle_only = three.js / Godot: N = int(mix(Nmax, Nmin, |V.z|)), no C.
// The complexity fetch is not a depth fetch and is not counted in `fetches`.
// #include "common/layer_march.wgsl"

fn adaptive_layer_count(uv0: vec2f, v: vec3f) -> u32 {
    let nmin = f32(trace_params.min_layers);  // the counts mix as real numbers; N is truncated at the end
    let nmax = f32(trace_params.max_layers);
    let cos_view = min(abs(v.z) / max(length(v), 1e-30), 1.0);  // |V.N| for a unit V
    var n: f32;
    if trace_params.angle_only != 0u {
        n = mix(nmax, nmin, cos_view);
    } else {
        let g = 1.0 - cos_view;
        let f = select(pow(g, 0.8), 0.0, g <= 0.0);  // pow(0, y) is undefined in WGSL
        let c = textureSampleLevel(complexity_tex, material_sampler, uv0, 0.0).r;
        n = mix(mix(nmin, 0.5 * nmax, f), mix(nmin, nmax, f), c);
    }
    return u32(clamp(floor(n), 1.0, f32(MAX_LAYERS)));
}

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    return pom_search(uv0, v, lod, 0.0, adaptive_layer_count(uv0, v));
}
