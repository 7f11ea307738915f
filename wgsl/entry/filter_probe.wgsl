// Compute probe of a texture filter: runs the filter's `filter_texture` (the function the fragment path uses)
// on given footprints over the texture bound as albedo_tex, and writes the value and the filter's statistics.
// FilterSample and FilterOut are generated from wgpuviewer/relief/filter_probe.py (FILTER_SAMPLE, FILTER_OUT),
// which fills the samples and reads the results by field name.
// #include "common/probe_index.wgsl"

@group(0) @binding(0) var<storage, read> samples: array<FilterSample>;
@group(0) @binding(1) var<storage, read_write> results: array<FilterOut>;

@compute @workgroup_size(64)
fn filter_probe_main(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let i = probe_index(id, groups);
    if i < arrayLength(&samples) {
        let s = samples[i];
        filter_stats = FilterStats(0u, 0u, 0u, 0u);
        let value = filter_texture(albedo_tex, Footprint(s.uv, s.dx, s.dy, s.view, 0.0));
        let f = filter_stats;
        results[i] = FilterOut(value, f.texels, f.depth_fetches, f.hidden, f.flags);
    }
}
