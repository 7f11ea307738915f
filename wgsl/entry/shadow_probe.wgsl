// Compute probe of self-shadowing: for given points in the relief (uv, layer depth t) and lights (tangent space,
// towards the light), the hard shadow through the technique's own `trace` and the soft estimate
// (common/shadow.wgsl), at mip level 0: what the renderer's shadowing variants compute per light. ShadowPoint and
// ShadowOut are generated from wgpuviewer/relief/probe.py (SHADOW_POINT, SHADOW_OUT).
// #include "common/probe_index.wgsl"
// #include "common/shadow.wgsl"

@group(0) @binding(0) var<storage, read> points: array<ShadowPoint>;
@group(0) @binding(1) var<storage, read_write> shadows: array<ShadowOut>;

@compute @workgroup_size(64)
fn shadow_main(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let i = probe_index(id, groups);
    if i >= arrayLength(&points) {
        return;
    }
    let p = points[i];
    let hard = shadow_hard(p.uv, p.depth, p.light, 0.0);
    let soft = shadow_soft(p.uv, p.light);
    shadows[i] = ShadowOut(hard.visibility, soft.visibility, hard.fetches, soft.fetches,
                           u32(hard.capped || soft.capped));
}
