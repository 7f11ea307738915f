// One level of the maximum pyramid: dst (ceil(w/2) x ceil(h/2)) from src (w x h).
// Parent i covers children floor(i*n/p) .. min(2i+1, n-1): a superset of both the index-space
// children 2i..2i+1 (clamped) and every child its UV span overlaps, so it stays conservative for
// odd and non-square sizes.
// #include "common/map_buffers.wgsl"

@compute @workgroup_size(8, 8)
fn reduce(@builtin(global_invocation_id) gid: vec3u) {
    let parent = gid.xy;
    if (any(parent >= P.dst_size)) { return; }
    let first = (parent * P.src_size) / P.dst_size;
    let last = min(min(2u * parent + 1u, P.src_size - 1u), first + 2u);  // at most 3 children per axis
    var m = src[first.y * P.src_size.x + first.x];
    for (var y = first.y; y <= last.y; y++) {
        for (var x = first.x; x <= last.x; x++) {
            m = max(m, src[y * P.src_size.x + x]);
        }
    }
    dst[parent.y * P.dst_size.x + parent.x] = m;
}
