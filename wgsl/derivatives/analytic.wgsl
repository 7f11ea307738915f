// Derivative source `analytic`: the local Jacobian of the hit. The hit uv_h = uv0 - t P with t = D(uv_h), so
// d uv_h = w - P (g . d uv_h) with w = d uv0 - t dP and g the relief slope at the hit; solved (Sherman-Morrison):
// d uv_h = w - P (g . w) / (1 + g . P). 1 + g . P >= 0 at a first hit (the ray enters the relief there); it
// vanishes where the ray grazes a slope (silhouettes), so it is kept >= 1 / DERIVATIVE_LIMIT and the result
// bounded like the displaced source. Unlike screen-space differences it does not jump at depth
// discontinuities: it is the footprint of the surface the pixel's centre hits. g: central differences of D
// one texel apart at level 0 (4 fetches, counted as filter depth fetches). Called in uniform control flow.
// #include "common/footprint.wgsl"

fn texture_derivatives(uv0: vec2f, v: vec3f, hit: TraceResult) -> Derivatives {
    let p = parallax_span(v);
    let dpx = dpdx(p);
    let dpy = dpdy(p);
    let d0x = dpdx(uv0);
    let d0y = dpdy(uv0);
    let h = 1.0 / vec2f(textureDimensions(depth_tex, 0));
    let gx = textureSampleLevel(depth_tex, material_sampler, hit.uv + vec2f(h.x, 0.0), 0.0).r
        - textureSampleLevel(depth_tex, material_sampler, hit.uv - vec2f(h.x, 0.0), 0.0).r;
    let gy = textureSampleLevel(depth_tex, material_sampler, hit.uv + vec2f(0.0, h.y), 0.0).r
        - textureSampleLevel(depth_tex, material_sampler, hit.uv - vec2f(0.0, h.y), 0.0).r;
    let g = vec2f(gx, gy) / (2.0 * h);
    filter_stats.depth_fetches += 4u;
    let denom = max(1.0 + dot(g, p), 1.0 / DERIVATIVE_LIMIT);
    let wx = d0x - hit.depth * dpx;
    let wy = d0y - hit.depth * dpy;
    return bounded_derivatives(wx - p * (dot(g, wx) / denom), wy - p * (dot(g, wy) / denom), d0x, d0y);
}
