// Compute probe of a texture filter: runs the filter's `filter_texture` (the function the fragment path uses)
// on given footprints over the texture bound as albedo_tex, and writes the value and the filter's statistics.
// FilterSample and FilterOut are checked against wgpuviewer/relief/filter_probe.py's strides by a test.

struct FilterSample {
    uv: vec2f,
    dx: vec2f,
    dy: vec2f,
    _pad: vec2f,
    view: vec4f,  // xyz: V in tangent space (visibility traces)
}

struct FilterOut {
    value: vec4f,
    texels: u32,
    depth_fetches: u32,
    hidden: u32,
    flags: u32,
}

@group(0) @binding(0) var<storage, read> samples: array<FilterSample>;
@group(0) @binding(1) var<storage, read_write> results: array<FilterOut>;

@compute @workgroup_size(64)
fn filter_probe_main(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let i = id.x + id.y * groups.x * 64u;
    if i >= arrayLength(&samples) {
        return;
    }
    let s = samples[i];
    filter_stats = FilterStats(0u, 0u, 0u, 0u);
    let value = filter_texture(albedo_tex, Footprint(s.uv, s.dx, s.dy, s.view.xyz, 0.0));
    results[i] = FilterOut(value, filter_stats.texels, filter_stats.depth_fetches, filter_stats.hidden,
                           filter_stats.flags);
}
