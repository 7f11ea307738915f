// 3D distance map (Donnelly) in the texel metric of docs/maps.md, three passes:
//   tops:    per texel, min (solid) or max (free space) of the depth D = 1 - H over the 3x3 texels around it (wrap)
//   pass_x:  g1(i, j, k) = min over columns qx of wrapdx^2 + ((E(qx, j) - t_k)^+ * S*W)^2   (solid; free: (t_k - E)^+)
//   pass_y:  d^2(i, j, k) = min over rows qy of (W/H)^2 wrapdy^2 + g1(i, qy, k); out = d (raw) or
//            max(0, d - half voxel diagonal - margin) (stored)
// Brute force over offsets: exact, O(W + H) per voxel, loops bounded by the map size (<= the volume limit).
// Volumes are f32 buffers indexed (k * H + j) * W + i.
// #include "common/map_buffers.wgsl"

struct Params {
    width: u32,
    height: u32,
    slices: u32,
    mode: u32,        // tops: 0 = min (solid), 1 = max (free space); pass_x: same; pass_y: 0 = raw d, 1 = stored
    sw: f32,          // S * W: metric length of the whole depth range t in [0, 1]
    aspect2: f32,     // (W / H)^2
    subtract: f32,    // half voxel diagonal + rounding margin (pass_y, mode 1)
    _pad: f32,
};

@compute @workgroup_size(8, 8, 1)
fn tops(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height || gid.z != 0u) { return; }
    let w = i32(P.width);
    let h = i32(P.height);
    var m = 1.0 - src[gid.y * P.width + gid.x];
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let d = 1.0 - src[u32(wrap_index(i32(gid.y) + dy, h) * w + wrap_index(i32(gid.x) + dx, w))];
            if (P.mode == 0u) { m = min(m, d); } else { m = max(m, d); }
        }
    }
    dst[gid.y * P.width + gid.x] = m;
}

@compute @workgroup_size(8, 8, 1)
fn pass_x(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height || gid.z >= P.slices) { return; }
    let t = (f32(gid.z) + 0.5) / f32(P.slices);
    let row = gid.y * P.width;
    var best = 3.0e38;
    for (var q = 0u; q < P.width; q++) {
        var gap = src[row + q] - t;
        if (P.mode == 1u) { gap = -gap; }
        let v = max(gap, 0.0) * P.sw;
        let a = max(q, gid.x) - min(q, gid.x);
        let dx = f32(min(a, P.width - a));
        best = min(best, dx * dx + v * v);
    }
    dst[(gid.z * P.height + gid.y) * P.width + gid.x] = best;
}

@compute @workgroup_size(8, 8, 1)
fn pass_y(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height || gid.z >= P.slices) { return; }
    let base = gid.z * P.height * P.width + gid.x;
    var best = 3.0e38;
    for (var q = 0u; q < P.height; q++) {
        let a = max(q, gid.y) - min(q, gid.y);
        let dy = f32(min(a, P.height - a));
        best = min(best, dy * dy * P.aspect2 + src[base + q * P.width]);
    }
    var d = sqrt(best);
    if (P.mode == 1u) { d = max(d - P.subtract, 0.0); }
    dst[(gid.z * P.height + gid.y) * P.width + gid.x] = d;
}
