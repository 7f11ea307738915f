// The item a probe invocation handles: large sets are dispatched as a 2D grid of 64-wide workgroups (65535 per
// dimension at most), folded back into one index here (wgpuviewer/relief/probe.py, dispatch).
fn probe_index(id: vec3u, groups: vec3u) -> u32 {
    return id.x + id.y * groups.x * 64u;
}
