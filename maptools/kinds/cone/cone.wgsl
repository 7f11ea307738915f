// Relaxed cone map (maptools/cone.py is the float64 twin; the argument is in docs/maps.md, "Relaxed cone map").
// Horizontal metric: x in texels of u, y = row * sy (sy = W/H); depth D = 1 - H in units of t.
// ratio: per texel q, min over the bilinear cells C met ring by ring (Chebyshev rings of cell offsets, at most
//   P.rings rings, stopped once (a - 0.5) * min(1, sy) >= c * (M_q - global min depth)) of
//     near cells (offsets -1..0): 1 / G_near        if C may contain an exit point and M_q > min corner(C)
//     far cells:                  rho / (M_q - min corner(C))   (same condition)
//   clamped to max_ratio and multiplied by (1 - margin).  min3x3: optional 3x3 min (filter = bilinear).
// #include "common/map_buffers.wgsl"

fn depth(i: i32, j: i32) -> f32 {
    let w = i32(P.width);
    let h = i32(P.height);
    return 1.0 - src[u32(wrap_index(j, h) * w + wrap_index(i, w))];
}

struct Cell {
    cmin: f32,
    amax: f32,
    amin: f32,
    bmax: f32,
    bmin: f32,
    mag: f32,
    grad: f32,
};

fn cell(i: i32, j: i32) -> Cell {
    let c00 = depth(i, j);
    let c10 = depth(i + 1, j);
    let c01 = depth(i, j + 1);
    let c11 = depth(i + 1, j + 1);
    let a0 = c10 - c00;
    let a1 = c11 - c01;
    let b0 = (c01 - c00) / P.sy;
    let b1 = (c11 - c10) / P.sy;
    let am = max(abs(a0), abs(a1));
    let bm = max(abs(b0), abs(b1));
    return Cell(min(min(c00, c10), min(c01, c11)), max(a0, a1), min(a0, a1), max(b0, b1), min(b0, b1), am + bm,
                sqrt(am * am + bm * bm));
}

fn axis_rho(d: i32) -> f32 {
    return max(0.0, max(f32(d) - 0.5, -f32(d) - 1.5));
}

fn hpart(x: f32, hi: f32, lo: f32) -> f32 {
    if (x >= 0.0) { return x * hi; }
    return x * lo;
}

// Bound contributed by the cell at offset (di, dj) from texel (i, j).
fn bound(i: i32, j: i32, di: i32, dj: i32, m: f32, g: f32) -> f32 {
    let c = cell(i + di, j + dj);
    let denom = m - c.cmin;
    if (c.mag <= 0.0 || denom <= 0.0) { return 3.0e38; }
    let x0 = f32(di) - 0.5;
    let x1 = f32(di) + 1.5;
    let y0 = (f32(dj) - 0.5) * P.sy;
    let y1 = (f32(dj) + 1.5) * P.sy;
    let hmax = max(hpart(x0, c.amax, c.amin), hpart(x1, c.amax, c.amin))
             + max(hpart(y0, c.bmax, c.bmin), hpart(y1, c.bmax, c.bmin));
    let band = P.band * c.mag * (max(abs(x0), abs(x1)) + max(abs(y0), abs(y1)) + 1.0);
    if (hmax <= -band) { return 3.0e38; }
    if ((di == -1 || di == 0) && (dj == -1 || dj == 0)) { return 1.0 / g; }
    let rx = axis_rho(di);
    let ry = axis_rho(dj) * P.sy;
    return sqrt(rx * rx + ry * ry) / denom;
}

@compute @workgroup_size(8, 8)
fn ratio(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height) { return; }
    let i = i32(gid.x);
    let j = i32(gid.y);
    var m = depth(i, j);
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) { m = max(m, depth(i + dx, j + dy)); }
    }
    var g = 0.0;
    for (var dy = -1; dy <= 0; dy++) {
        for (var dx = -1; dx <= 0; dx++) { g = max(g, cell(i + dx, j + dy).grad); }
    }
    let reach = m - P.dmin;
    let unit = min(1.0, P.sy);
    var c = P.max_ratio;
    for (var a = 0; a < i32(P.rings); a++) {
        if (a >= 1 && (f32(a) - 0.5) * unit >= c * reach) { break; }
        for (var di = -a - 1; di <= a; di++) {           // bottom and top rows of the ring
            c = min(c, bound(i, j, di, -a - 1, m, g));
            c = min(c, bound(i, j, di, a, m, g));
        }
        for (var dj = -a; dj < a; dj++) {                // left and right columns
            c = min(c, bound(i, j, -a - 1, dj, m, g));
            c = min(c, bound(i, j, a, dj, m, g));
        }
    }
    dst[gid.y * P.width + gid.x] = max(c * P.keep, 0.0);
}

@compute @workgroup_size(8, 8)
fn min3x3(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height) { return; }
    let w = i32(P.width);
    let h = i32(P.height);
    var c = src[gid.y * P.width + gid.x];
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            c = min(c, src[u32(wrap_index(i32(gid.y) + dy, h) * w + wrap_index(i32(gid.x) + dx, w))]);
        }
    }
    dst[gid.y * P.width + gid.x] = c;
}
