// The relief search (Policarpo et al.), shared by relief and auto: the layer march (common/layer_march.wgsl) finds
// the first layer on or below the surface, binary_steps halvings shrink the bracket [last layer above, that layer],
// and the secant through the final bracket's two ends ends it (secant_finish). Bounded: at most n + 1 + nb fetches.
// #include "common/layer_march.wgsl"

// A bracket of layer depths along the ray uv(t) = uv0 - span * t: t.x above the surface (free: t < depth there),
// t.y on or below it (solid), and the depth map's depth at each end (fetched by the search: the finish needs no more).
struct Bracket {
    t: vec2f,
    d: vec2f,
}

// n halvings of the bracket; each keeps one end free and the other solid, with its depth.
fn binary_refine(uv0: vec2f, span: vec2f, bracket: Bracket, n: u32, lod: f32) -> Bracket {
    var b = bracket;
    for (var k = 0u; k < n; k++) {
        let mid = 0.5 * (b.t.x + b.t.y);
        let d = depth_at(uv0 - span * mid, lod);
        if mid >= d {
            b.t.y = mid;
            b.d.y = d;
        } else {
            b.t.x = mid;
            b.d.x = d;
        }
    }
    return b;
}

// Where the line through the bracket's two ends (t, depth(t)) meets t = depth: the surface's crossing if it is
// linear over the bracket. Measured against the bracket's midpoint at equal fetches (docs/techniques.md, relief):
// error near 0 where the midpoint errs by up to half the bracket, and within 1 % of it where the layers stepped over
// the first hit. Between the ends: above > 0 >= below, so the weight lies in (0, 1]; the clamp keeps the hit in the
// bracket where rounding breaks that (a march that ends at the range's bottom a rounding short of the deepest depth),
// and a flush-to-zero difference (denominator 0) ends at the free end.
fn secant_finish(b: Bracket) -> f32 {
    let above = b.d.x - b.t.x;  // > 0: the free end is above the surface
    let below = b.d.y - b.t.y;  // <= 0: the solid end is on or below it
    let denom = above - below;
    let w = select(0.0, clamp(above / denom, 0.0, 1.0), denom > 0.0);
    return b.t.x + w * (b.t.y - b.t.x);
}

// The relief search: n layers of the depth range, nb halvings, the secant finish. With nb = 0 it is POM (to rounding).
fn relief_search(uv0: vec2f, v: vec3f, lod: f32, n: u32, nb: u32) -> TraceResult {
    let m = layer_march(uv0, v, lod, 0.0, n);
    if m.layers == 0u {
        return TraceResult(m.uv, m.t_start, fetch_count, is_grazing(v), n);
    }
    let solid = m.t_start + f32(m.layers) * m.layer_step;
    let span = parallax_span(v);
    let b = binary_refine(uv0, span, Bracket(vec2f(solid - m.layer_step, solid), vec2f(m.d_prev, m.d)), nb, lod);
    let t = secant_finish(b);
    return TraceResult(uv0 - span * t, t, fetch_count, is_grazing(v), n);
}
