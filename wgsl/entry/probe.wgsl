// Compute probe: runs a technique's `trace` on given rays (the same function the fragment path uses), at mip
// level 0, with each ray's pixel footprint (uv per pixel along screen x and y; zero: none), and writes what it found
// per ray. ProbeRay and ProbeHit are generated from wgpuviewer/relief/probe.py (PROBE_RAY, PROBE_HIT), which fills
// the rays and reads the hits by field name.
// #include "common/probe_index.wgsl"

@group(0) @binding(0) var<storage, read> rays: array<ProbeRay>;
@group(0) @binding(1) var<storage, read_write> hits: array<ProbeHit>;

@compute @workgroup_size(64)
fn probe_main(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let i = probe_index(id, groups);
    if i >= arrayLength(&rays) {
        return;
    }
    pixel_footprint = mat2x2f(rays[i].dx, rays[i].dy);  // zero: no footprint
    let r = trace(rays[i].uv, rays[i].view, 0.0);
    hits[i] = ProbeHit(r.uv, r.depth, r.fetches, u32(r.capped), r.layers);
}
