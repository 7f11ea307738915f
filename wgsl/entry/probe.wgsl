// Compute probe: runs a technique's `trace` on given rays (the same function the fragment path
// uses), at mip level 0, and writes what it found per ray. ProbeRay and ProbeHit are checked against
// wgpuviewer/relief/probe.py's strides by a test.
// #include "common/probe_index.wgsl"

struct ProbeRay {
    uv: vec2f,
    _pad: vec2f,
    view: vec4f,  // xyz: V in tangent space
}

struct ProbeHit {
    uv: vec2f,
    depth: f32,
    fetches: u32,
    capped: u32,
    layers: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<storage, read> rays: array<ProbeRay>;
@group(0) @binding(1) var<storage, read_write> hits: array<ProbeHit>;

@compute @workgroup_size(64)
fn probe_main(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let i = probe_index(id, groups);
    if i >= arrayLength(&rays) {
        return;
    }
    let r = trace(rays[i].uv, rays[i].view.xyz, 0.0);
    hits[i] = ProbeHit(r.uv, r.depth, r.fetches, u32(r.capped), r.layers, 0u, 0u);
}
