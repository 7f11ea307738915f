// The exact solve of one bilinear cell (maxmip, distance, quadmax; the float64 twin is wgpuviewer/relief/reference.py)
// and where a ray leaves a box of cells.
// #include "common/depth.wgsl"

// Smallest s in [0, len] with a s^2 + b s + c = 0 given c < 0 (f = t - D below zero at s = 0), or -1.
// Cancellation-free pair q/a, c/q; a == 0 (linear) falls out as -c/b. Roots a rounding error past the
// interval are accepted (clamped): the caller's next cell would catch them at its entry anyway.
fn first_root(a: f32, b: f32, c: f32, len: f32) -> f32 {
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return -1.0;
    }
    let q = -0.5 * (b + select(-1.0, 1.0, b >= 0.0) * sqrt(disc));
    let slack = 1e-6 * max(len, 1.0);
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
    fetch_count += 1u;
    let size = vec2f(textureDimensions(depth_tex, 0));
    // Gather order: (umin, vmax), (umax, vmax), (umax, vmin), (umin, vmin).
    let g = textureGather(0, depth_tex, material_sampler, (vec2f(cell) + 1.0) / size);
    return cell_root(vec4f(g.w, g.z, g.x, g.y), cell, start, dir, t0, t1);
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
    let qc = t0 - (c00 + bx * e.x + cy * e.y + exy * e.x * e.y);
    if qc >= 0.0 {
        return t0;
    }
    let qb = 1.0 - (bx * dir.x + cy * dir.y + exy * (e.x * dir.y + e.y * dir.x));
    let qa = -exy * dir.x * dir.y;
    let s = first_root(qa, qb, qc, max(t1 - t0, 0.0));
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
