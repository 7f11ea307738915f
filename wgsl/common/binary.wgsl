// Binary refinement (relief, cone): n halvings of a bracket [lo, hi] of layer depths along the ray
// uv(t) = uv0 - span * t, lo above the surface (free) and hi below it (solid); each halving keeps that.
// #include "common/depth.wgsl"

fn binary_refine(uv0: vec2f, span: vec2f, lo: f32, hi: f32, n: u32, lod: f32) -> vec2f {
    var bracket = vec2f(lo, hi);
    for (var k = 0u; k < n; k++) {
        let mid = 0.5 * (bracket.x + bracket.y);
        if mid >= depth_at(uv0 - span * mid, lod) {
            bracket.y = mid;
        } else {
            bracket.x = mid;
        }
    }
    return bracket;
}
