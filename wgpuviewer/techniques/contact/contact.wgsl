// Contact-refinement parallax: the layer march (common/layer_march.wgsl) finds the first of linear_steps equal layers
// of the depth range on or below the surface; a second linear search steps through that layer's bracket [last layer
// above, that layer] in refine_steps equal sub-steps up to the first one on or below the surface; the secant through
// the final sub-bracket's two ends gives the hit (secant_finish, common/binary.wgsl, relief's finish: no extra fetch).
// With refine_steps = 1 this is POM. Bounded: at most linear_steps + 1 + refine_steps - 1 fetches (the sub-step at the
// bracket's solid end is the march's own sample, not fetched again).
// #include "common/binary.wgsl"

// The second linear search: sub-steps k = 1 .. m - 1 of the bracket, from its free end on; stops at the first one on
// or below the surface (then the bracket is [the sub-step before, it]); past the last one, [last sub-step, solid end].
fn contact_refine(uv0: vec2f, span: vec2f, bracket: Bracket, m: u32, lod: f32) -> Bracket {
    var b = bracket;
    let t_free = bracket.t.x;
    let step = (bracket.t.y - t_free) / f32(m);
    for (var k = 1u; k < m; k++) {
        let t = t_free + f32(k) * step;
        let d = depth_at(uv0 - span * t, lod);
        if t >= d {
            b.t.y = t;
            b.d.y = d;
            return b;
        }
        b.t.x = t;
        b.d.x = d;
    }
    return b;
}

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let n = clamp(trace_params.linear_steps, LINEAR_STEPS_MIN, LINEAR_STEPS_MAX);
    let m = clamp(trace_params.refine_steps, REFINE_STEPS_MIN, REFINE_STEPS_MAX);
    let march = layer_march(uv0, v, lod, 0.0, n);
    if march.layers == 0u {
        return TraceResult(march.uv, march.t_start, fetch_count, is_grazing(v), n);
    }
    let solid = march.t_start + f32(march.layers) * march.layer_step;
    let span = parallax_span(v);
    let bracket = Bracket(vec2f(solid - march.layer_step, solid), vec2f(march.d_prev, march.d));
    let t = secant_finish(contact_refine(uv0, span, bracket, m, lod));
    return TraceResult(uv0 - span * t, t, fetch_count, is_grazing(v), n);
}
