// The plain 3D distance map (maptools/distance.py is the CPU twin; docs/maps.md the metric and the argument):
// per voxel the exact distance from its (grown) box to the outer solid of K x K sub-cell columns per bilinear cell.
//   tops:       per sub-cell, the least bilinear depth at its four corners, times S*W (metric Z of the column top)
//   pass_x:     g(i, b, k) = min over sub-cell columns a of row b: gap_u(i, a)^2 + max(top - box bottom, 0)^2
//   pass_y:     d(i, j, k)^2 = min over sub-cell rows b: gap_v(j, b)^2 + g(i, b, k); stored max(d - margin, 0)
// The passes walk offsets outwards in pairs of equal gap and stop once the gap alone reaches the best value: exact,
// bounded by half a period. Volumes are f32 buffers indexed (k * rows + row) * W + i, k the slice within the slab
// baked (slices [first_slice, first_slice + slices): maptools/gpu.py bakes large volumes slab by slab).
// #include "common/map_buffers.wgsl"

// Bilinear depth (repeat) at the sub-cell vertex (a, b): X = 0.5 + a / K, Y = (0.5 + b / K) * sy.
fn vertex_depth(a: u32, b: u32) -> f32 {
    let k = P.subcells;
    let x0 = a / k;
    let y0 = b / k;
    let x1 = (x0 + 1u) % P.width;
    let y1 = (y0 + 1u) % P.height;
    let fx = f32(a % k) / f32(k);
    let fy = f32(b % k) / f32(k);
    let r0 = (1.0 - src[y0 * P.width + x0]) * (1.0 - fx) + (1.0 - src[y0 * P.width + x1]) * fx;
    let r1 = (1.0 - src[y1 * P.width + x0]) * (1.0 - fx) + (1.0 - src[y1 * P.width + x1]) * fx;
    return r0 * (1.0 - fy) + r1 * fy;
}

@compute @workgroup_size(8, 8, 1)
fn tops(@builtin(global_invocation_id) gid: vec3u) {
    let wk = P.width * P.subcells;
    let hk = P.height * P.subcells;
    if (gid.x >= wk || gid.y >= hk || gid.z != 0u) { return; }
    let a1 = (gid.x + 1u) % wk;
    let b1 = (gid.y + 1u) % hk;
    let m = min(min(vertex_depth(gid.x, gid.y), vertex_depth(a1, gid.y)),
                min(vertex_depth(gid.x, b1), vertex_depth(a1, b1)));
    dst[gid.y * wk + gid.x] = m * P.sw;
}

// Gap along one axis between a voxel box (half-extent step / 2 + grow) and the sub-cell K n + o (or K n - 1 - o) of
// its own index n, o >= 0: that sub-cell covers [o / K, (o + 1) / K] * step from the voxel centre.
fn subcell_gap(o: u32, step: f32) -> f32 {
    return max(f32(o) / f32(P.subcells) * step - (0.5 * step + P.grow), 0.0);
}

@compute @workgroup_size(8, 8, 1)
fn pass_x(@builtin(global_invocation_id) gid: vec3u) {
    let wk = i32(P.width * P.subcells);
    let hk = P.height * P.subcells;
    if (gid.x >= P.width || gid.y >= hk || gid.z >= P.slices) { return; }
    let bottom = f32(P.first_slice + gid.z + 1u) * P.dz + P.grow;
    let base = i32(gid.x * P.subcells);
    let row = gid.y * u32(wk);
    var best = 3.0e38;
    for (var o = 0u; o <= u32(wk) / 2u; o++) {
        let g = subcell_gap(o, 1.0);
        if (g * g >= best) { break; }
        let v0 = max(src[row + u32(wrap_index(base + i32(o), wk))] - bottom, 0.0);
        let v1 = max(src[row + u32(wrap_index(base - 1 - i32(o), wk))] - bottom, 0.0);
        best = min(best, g * g + min(v0 * v0, v1 * v1));
    }
    dst[(gid.z * hk + gid.y) * P.width + gid.x] = best;
}

@compute @workgroup_size(8, 8, 1)
fn pass_y(@builtin(global_invocation_id) gid: vec3u) {
    let hk = i32(P.height * P.subcells);
    if (gid.x >= P.width || gid.y >= P.height || gid.z >= P.slices) { return; }
    let base = i32(gid.y * P.subcells);
    let plane = gid.z * u32(hk) * P.width + gid.x;
    var best = 3.0e38;
    for (var o = 0u; o <= u32(hk) / 2u; o++) {
        let g = subcell_gap(o, P.sy);
        if (g * g >= best) { break; }
        let v0 = src[plane + u32(wrap_index(base + i32(o), hk)) * P.width];
        let v1 = src[plane + u32(wrap_index(base - 1 - i32(o), hk)) * P.width];
        best = min(best, g * g + min(v0, v1));
    }
    dst[(gid.z * P.height + gid.y) * P.width + gid.x] = max(sqrt(best) - P.margin, 0.0);
}
