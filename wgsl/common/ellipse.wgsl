// The pixel footprint as an ellipse in texel space (Heckbert 1989), shared by the EWA filters, ewa_approx and
// aniso's texel estimate; the float64 twin is wgpuviewer/studies/filtering/cpu.py.
// #include "common/footprint.wgsl"

// A U^2 + B U V + C V^2 = F (U, V texel offsets from the centre) is the image of the unit pixel circle under
// the Jacobian with columns dx, dy (texels per pixel): A = vx^2 + vy^2, B = -2 (ux vx + uy vy),
// C = ux^2 + uy^2, F = (ux vy - uy vx)^2 (= A C - B^2 / 4).
struct Ellipse {
    a: f32,
    b: f32,
    c: f32,
    f: f32,
}

fn ellipse_coefficients(dx: vec2f, dy: vec2f) -> Ellipse {
    let det = dx.x * dy.y - dy.x * dx.y;
    return Ellipse(dx.y * dx.y + dy.y * dy.y, -2.0 * (dx.x * dx.y + dy.x * dy.y), dx.x * dx.x + dy.x * dy.x, det * det);
}

// Semi-axes of that ellipse (the singular values of the Jacobian, texels), major first, and the unit
// direction of the major axis ((1, 0) for a circle).
struct Axes {
    major: f32,
    minor: f32,
    dir: vec2f,
}

fn footprint_axes(dx: vec2f, dy: vec2f) -> Axes {
    // J J^T = [[p, r], [r, q]] = [[C, -B/2], [-B/2, A]]
    let e = ellipse_coefficients(dx, dy);
    let p = e.c;
    let q = e.a;
    let r = -0.5 * e.b;
    let mean = 0.5 * (p + q);
    let spread = sqrt(0.25 * (p - q) * (p - q) + r * r);
    let big = mean + spread;
    let small = max(mean - spread, 0.0);
    // Eigenvector of `big`: (r, big - p) or (big - q, r), whichever is longer (both vanish for a circle).
    let d1 = vec2f(r, big - p);
    let d2 = vec2f(big - q, r);
    let d = select(d2, d1, dot(d1, d1) >= dot(d2, d2));
    let n = length(d);
    return Axes(sqrt(big), sqrt(small), select(vec2f(1.0, 0.0), d / n, n > 1e-30 * max(big, 1e-30)));
}
