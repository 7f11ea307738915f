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

// The bound of every band for a column rho away whose top is z0 below the box.
fn bound(rho: f32, z0: f32) -> vec4f {
    let r = max(vec4f(rho), z0 * P.tan_lo);
    let depth = max(vec4f(z0), r * P.cot_hi);
    return sqrt(r * r + depth * depth);
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
    // lanes past `bands` start done: their value is the cap, and nothing is written for them
    let unused = vec4<bool>(P.bands < 1u, P.bands < 2u, P.bands < 3u, P.bands < 4u);
    var best = P.cap;
    var done = unused | (best <= plain);
    for (var q = 0u; q < P.count;) {
        let c = columns[q];
        done = done | (vec4f(c.rho) * P.inv_sin_hi >= best) | (best <= plain);
        if (all(done)) { break; }
        let b = bound(c.rho, max(column_top(c, gid.x, gid.y) - bottom, 0.0));
        let children = c.kind >> 8u;
        if (children == 0u) {
            best = select(min(best, b), best, done);
        } else if (any((b < best) & !done)) {
            for (var s = q + 1u; s <= q + children; s++) {
                let d = columns[s];
                let open = !done & (vec4f(d.rho) * P.inv_sin_hi < best) & (best > plain);
                if (!any(open)) { break; }
                best = select(best, min(best, bound(d.rho, max(column_top(d, gid.x, gid.y) - bottom, 0.0))), open);
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
