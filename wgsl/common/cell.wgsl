// The exact solve of one bilinear cell (maxmip, distance, quadmax; the float64 twin is wgpuviewer/relief/reference.py),
// where a ray leaves a box of cells, and the nodes of the pyramid walks (maxmip, quadmax).
// #include "common/depth.wgsl"
// #include "common/wrap.wgsl"

// A root this close outside a cell's t-interval is rounding and is accepted: 2^-22 of t (two float32 ulps of t
// there: a grazing ray's position along the ray) plus 2^-22 in f = t - D (the rounding of its O(1) terms) over
// f's slope. No more: past the interval the quadratic continues this cell's patch, not the surface, and a grazing
// ray passing just above a peak or ridge on a cell border meets that continuation just past the border. (A fixed
// slack of 1e-6 in t took a ray at 89.9 degrees passing 1.4e-4 above the spike's tip for a hit, 141.9 texels before
// the true one.) A true root just past the border is the next cell's, at its entry.
const ROOT_SLACK: f32 = 2.3841858e-7;

// Smallest s in [0, len] with a s^2 + b s + c = 0 given c < 0 (f = t - D below zero at s = 0), or -1; roots within
// `slack` outside [0, len] count, clamped. Cancellation-free pair q/a, c/q; a == 0 (linear) falls out as -c/b.
fn first_root(a: f32, b: f32, c: f32, len: f32, slack: f32) -> f32 {
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return -1.0;
    }
    let q = -0.5 * (b + select(-1.0, 1.0, b >= 0.0) * sqrt(disc));
    var best = 3.0e38;
    if a != 0.0 {
        let r = q / a;
        if r >= -slack && r <= len + slack { best = min(best, r); }
    }
    if q != 0.0 {
        let r = c / q;
        if r >= -slack && r <= len + slack { best = min(best, r); }
    }
    if best > 2.0e38 {
        return -1.0;
    }
    return clamp(best, 0.0, len);
}

// The exact first hit inside one bilinear cell (between texel centres cell and cell + 1, texel
// coordinates x = u * W - 0.5), for the ray p(t) = start + t * dir over [t0, t1]: f(t) = t - D(p(t))
// is a quadratic there (as in wgpuviewer/reference.py). Returns t of the hit, or -1. The cell's four
// depths come from one textureGather (counted as one fetch), addressed by the material sampler.
fn cell_hit(cell: vec2i, start: vec2f, dir: vec2f, t0: f32, t1: f32) -> f32 {
    return cell_root(cell_corners(cell), cell, start, dir, t0, t1);
}

// The cell's corner depths (c00, c10, c01, c11) (x = +u, y = +v): one textureGather, counted as one fetch.
fn cell_corners(cell: vec2i) -> vec4f {
    fetch_count += 1u;
    let size = vec2f(textureDimensions(depth_tex, 0));
    // Gather order: (umin, vmax), (umax, vmax), (umax, vmin), (umin, vmin).
    let g = textureGather(0, depth_tex, material_sampler, (vec2f(cell) + 1.0) / size);
    return vec4f(g.w, g.z, g.x, g.y);
}

// The bilinear depth at offset e in [0, 1]^2 inside a cell with corner depths c: cell_root's surface.
fn cell_depth(c: vec4f, e: vec2f) -> f32 {
    return c.x + (c.y - c.x) * e.x + (c.z - c.x) * e.y + (c.w - c.y - c.z + c.x) * e.x * e.y;
}

// cell_hit's solve for given corner depths c = (c00, c10, c01, c11) (x = +u, y = +v): no fetch.
fn cell_root(c: vec4f, cell: vec2i, start: vec2f, dir: vec2f, t0: f32, t1: f32) -> f32 {
    let c00 = c.x;
    let c10 = c.y;
    let c01 = c.z;
    let c11 = c.w;
    let bx = c10 - c00;
    let cy = c01 - c00;
    let exy = c11 - c10 - c01 + c00;
    let e = clamp(start + t0 * dir - vec2f(cell), vec2f(0.0), vec2f(1.0));
    let qc = t0 - cell_depth(c, e);
    if qc >= 0.0 {
        return t0;
    }
    let qb = 1.0 - (bx * dir.x + cy * dir.y + exy * (e.x * dir.y + e.y * dir.x));
    let qa = -exy * dir.x * dir.y;
    let len = max(t1 - t0, 0.0);
    let s = first_root(qa, qb, qc, len, ROOT_SLACK * (t0 + len + 1.0 / max(abs(qb), 1.0)));
    if s >= 0.0 {
        return t0 + s;
    }
    if t1 >= 1.0 {
        return 1.0;  // f(1) = 1 - D >= 0: a root lost to rounding at the floor of the relief
    }
    return -1.0;
}

// t at which the ray start + t * dir leaves the box [lo, hi] across x and across y.
fn box_exit(start: vec2f, dir: vec2f, lo: vec2f, hi: vec2f) -> vec2f {
    var r = vec2f(3.0e38);
    if dir.x > 0.0 { r.x = (hi.x - start.x) / dir.x; } else if dir.x < 0.0 { r.x = (lo.x - start.x) / dir.x; }
    if dir.y > 0.0 { r.y = (hi.y - start.y) / dir.y; } else if dir.y < 0.0 { r.y = (lo.y - start.y) / dir.y; }
    return r;
}

// The cell the ray enters when it leaves the box [lo, hi) of cells at t_exit (exits: where it crosses the box's x and
// y sides; through a corner both indices move). Integer state: rounding can never make a walk stall or go back.
fn next_cell(start: vec2f, dir: vec2f, t_exit: f32, exits: vec2f, lo: vec2i, hi: vec2i) -> vec2i {
    let p = floor(start + t_exit * dir);
    return vec2i(
        select(clamp(i32(p.x), lo.x, hi.x - 1), select(lo.x - 1, hi.x, dir.x > 0.0), exits.x <= t_exit),
        select(clamp(i32(p.y), lo.y, hi.y - 1), select(lo.y - 1, hi.y, dir.y > 0.0), exits.y <= t_exit),
    );
}

// A node of a pyramid walk: level m holds 2^m x 2^m cells, clipped at the map's edge (size wh cells, repeat).
struct WalkNode {
    index: vec2i,   // the node's (wrapped) index at its level
    lo: vec2i,      // its cells [lo, hi), unwrapped like the cell it was found from
    hi: vec2i,
    exits: vec2f,   // where the ray start + t * dir leaves them across x and across y
    t_exit: f32,    // the first of the two, at most 1
}

fn walk_node(cell: vec2i, level: u32, wh: vec2i, start: vec2f, dir: vec2f) -> WalkNode {
    let wrapped = wrap_texel(cell, wh);
    let index = wrapped >> vec2u(level);
    let first = index << vec2u(level);
    let lo = cell - wrapped + first;
    let hi = lo + min(vec2i(1 << level), wh - first);
    let exits = box_exit(start, dir, vec2f(lo), vec2f(hi));
    return WalkNode(index, lo, hi, exits, min(min(exits.x, exits.y), 1.0));
}
