// One azimuth sector of the refined distance map, all its polar bands at once (up to 4, one per vec4 lane), one
// invocation per voxel (maptools/refined.py: `bake` is the CPU twin, docs/maps.md the argument). The sector's
// columns come as a list (maptools.refined.entries): sub-cells, cells and windows of cells, each with rho, the
// least horizontal length towards it within the sector's azimuth wedge (voxel and band independent). Per column,
// with z0 the drop from the voxel box's bottom to the column top, every ray of band [a, b] from the box reaches it
// no sooner than
//     bound(rho, z0) = sqrt(r^2 + max(z0, r cot b)^2),   r = max(rho, z0 tan a),
// which grows with rho and with z0. Value = max(plain value, least bound - margin), the bound capped at
// reach / sin b. Cells and windows are sorted by rho: a band is done once rho / sin b (a bound for every later
// column) reaches its value, or its value is down to the plain one; the walk stops when every band is done. A near
// cell is a header followed by its sub-cells (sorted by rho): they are looked at only when the whole cell's bound
// can beat a band's value. Column offsets come pre-wrapped into [0, period).
//   window_tops: per cell and level L, the top of the window of 2^(L-1) x 2^(L-1) cells (least texel depth) x S*W
//   main:        src = the stored plain values, dst = the bands' volumes (band, slice, row, column), both of the slab
//                of slices [first_slice, first_slice + slices) (maptools/gpu.py bakes large volumes slab by slab)
// The paper's visibility condition (P.visibility = 1; maptools/refined.py `horizon` is the CPU twin): a voxel is
// read only by rays that reach it unblocked, whose polar angle is at most arccot(g) for the sector. Then every
// band's largest polar angle b is cut to that per voxel (never below the band's least angle a):
//   inner_tops:  src = the height map, dst = the inner solid's cell tops (the deepest corner) x S*W
//   horizon:     src = inner_tops' output, dst = the slab's cut (cot, widened by the bins' slack; 0: none):
//                g = max over rings n of (top of the box - the deepest inner top of ring n) / (n step)
// #include "common/map_buffers.wgsl"

struct Column {
    ox: u32,      // offset from the voxel's own sub-cell (level 0) or cell (level >= 1), modulo the period
    oy: u32,
    kind: u32,    // level (0: sub-cell; L: window of 2^(L-1) cells, 1 = a cell) | children << 8 (a header's sub-cells)
    rho: f32,     // rounded down
};

@group(0) @binding(3) var<storage, read> sub_tops: array<f32>;   // (H K, W K), metric Z of the sub-cell tops
@group(0) @binding(4) var<storage, read> windows: array<f32>;    // (levels, H, W), from window_tops
@group(0) @binding(5) var<storage, read> columns: array<Column>;
@group(0) @binding(6) var<storage, read> reach_cot: array<f32>;  // (slices, H, W) of the slab, from `horizon`
@group(0) @binding(7) var<storage, read> rings: array<vec2u>;    // the sector's ring offsets (ox, oy), pre-wrapped
@group(0) @binding(8) var<storage, read> ring_ends: array<u32>;  // ring n's offsets end at ring_ends[n]

// x + o for x, o in [0, n): brought back into [0, n).
fn wrapped(x: u32, o: u32, n: u32) -> u32 {
    let s = x + o;
    return select(s, s - n, s >= n);
}

fn column_top(c: Column, i: u32, j: u32) -> f32 {
    let level = c.kind & 255u;
    if (level == 0u) {
        let wk = P.width * P.subcells;
        return sub_tops[wrapped(j * P.subcells, c.oy, P.height * P.subcells) * wk + wrapped(i * P.subcells, c.ox, wk)];
    }
    return windows[((level - 1u) * P.height + wrapped(j, c.oy, P.height)) * P.width + wrapped(i, c.ox, P.width)];
}

// The bound of every band for a column rho away whose top is z0 below the box; cot_hi: of each band's largest
// polar angle that reaches the voxel.
fn bound(rho: f32, z0: f32, cot_hi: vec4f) -> vec4f {
    let r = max(vec4f(rho), z0 * P.tan_lo);
    let depth = max(vec4f(z0), r * cot_hi);
    return sqrt(r * r + depth * depth);
}

@compute @workgroup_size(8, 8, 1)
fn inner_tops(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height) { return; }
    let row = gid.y * P.width;
    let next = ((gid.y + 1u) % P.height) * P.width;
    let right = (gid.x + 1u) % P.width;
    let least = min(min(src[row + gid.x], src[row + right]), min(src[next + gid.x], src[next + right]));
    dst[row + gid.x] = (1.0 - least) * P.sw;
}

@compute @workgroup_size(8, 8, 1)
fn horizon(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height) { return; }
    let area = P.width * P.height;
    let index = gid.y * P.width + gid.x;
    for (var k = 0u; k < P.slices; k++) { dst[k * area + index] = 0.0; }
    var start = 0u;
    for (var n = 0u; n < P.rings; n++) {
        let end = ring_ends[n];
        // blocked only below every inner column the ring touches: below the deepest top (largest Z)
        let empty = end == start;
        var deepest = -3.0e38;
        for (var q = start; q < end; q++) {
            let o = rings[q];
            deepest = max(deepest, src[wrapped(gid.y, o.y, P.height) * P.width + wrapped(gid.x, o.x, P.width)]);
        }
        start = end;
        if (empty) { continue; }
        let x = f32(n + 1u) * P.horizon_step;
        for (var k = 0u; k < P.slices; k++) {
            let top = f32(P.first_slice + k) * P.dz - P.grow;
            dst[k * area + index] = max(dst[k * area + index], (top - deepest) / x);
        }
    }
    for (var k = 0u; k < P.slices; k++) {
        let g = dst[k * area + index];
        dst[k * area + index] = max((g * P.cot_slack - 1.0) / (g + P.cot_slack), 0.0);
    }
}

@compute @workgroup_size(8, 8, 1)
fn window_tops(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height || gid.z >= P.levels) { return; }
    let size = 1u << gid.z;
    var top = 3.0e38;
    for (var y = 0u; y <= size; y++) {
        let row = ((gid.y + y) % P.height) * P.width;
        for (var x = 0u; x <= size; x++) {
            top = min(top, 1.0 - src[row + (gid.x + x) % P.width]);
        }
    }
    dst[(gid.z * P.height + gid.y) * P.width + gid.x] = top * P.sw;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height || gid.z >= P.slices) { return; }
    let index = (gid.z * P.height + gid.y) * P.width + gid.x;
    let plain = vec4f(src[index]);
    let bottom = f32(P.first_slice + gid.z + 1u) * P.dz + P.grow;
    var cot_hi = P.cot_hi;
    var inv_sin_hi = P.inv_sin_hi;
    var best = P.cap;
    if (P.visibility != 0u) {
        let cut = vec4f(reach_cot[index]) > P.cot_hi;
        var cot = select(P.cot_hi, vec4f(reach_cot[index]), cut);
        cot = select(cot, 1.0 / P.tan_lo, cot * P.tan_lo > vec4f(1.0));  // not below the band's least angle
        cot_hi = cot;
        inv_sin_hi = select(P.inv_sin_hi, sqrt(1.0 + cot * cot), cut);
        best = select(P.cap, P.reach * inv_sin_hi, cut);
    }
    // lanes past `bands` start done: their value is the cap, and nothing is written for them
    let unused = vec4<bool>(P.bands < 1u, P.bands < 2u, P.bands < 3u, P.bands < 4u);
    var done = unused | (best <= plain);
    for (var q = 0u; q < P.count;) {
        let c = columns[q];
        done = done | (vec4f(c.rho) * inv_sin_hi >= best) | (best <= plain);
        if (all(done)) { break; }
        let b = bound(c.rho, max(column_top(c, gid.x, gid.y) - bottom, 0.0), cot_hi);
        let children = c.kind >> 8u;
        if (children == 0u) {
            best = select(min(best, b), best, done);
        } else if (any((b < best) & !done)) {
            for (var s = q + 1u; s <= q + children; s++) {
                let d = columns[s];
                let open = !done & (vec4f(d.rho) * inv_sin_hi < best) & (best > plain);
                if (!any(open)) { break; }
                let z0 = max(column_top(d, gid.x, gid.y) - bottom, 0.0);
                best = select(best, min(best, bound(d.rho, z0, cot_hi)), open);
            }
        }
        q += 1u + children;
    }
    let value = max(plain, best - P.margin);
    let volume = P.slices * P.height * P.width;
    for (var band = 0u; band < P.bands; band++) {
        dst[band * volume + index] = value[band];
    }
}
