// One level of the maximum pyramid: dst (ceil(w/2) x ceil(h/2)) from src (w x h).
// Parent i covers children floor(i*n/p) .. min(2i+1, n-1): a superset of both the index-space
// children 2i..2i+1 (clamped) and every child its UV span overlaps, so it stays conservative for
// odd and non-square sizes.
// #include "common/map_buffers.wgsl"

struct Params {
    src_w: u32,
    src_h: u32,
    dst_w: u32,
    dst_h: u32,
};

@compute @workgroup_size(8, 8)
fn reduce(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.dst_w || gid.y >= P.dst_h) { return; }
    let x0 = (gid.x * P.src_w) / P.dst_w;
    let x1 = min(2u * gid.x + 1u, P.src_w - 1u);
    let y0 = (gid.y * P.src_h) / P.dst_h;
    let y1 = min(2u * gid.y + 1u, P.src_h - 1u);
    var m = src[y0 * P.src_w + x0];
    for (var y = y0; y <= min(y1, y0 + 2u); y++) {      // at most 3 children per axis
        for (var x = x0; x <= min(x1, x0 + 2u); x++) {
            m = max(m, src[y * P.src_w + x]);
        }
    }
    dst[gid.y * P.dst_w + gid.x] = m;
}
