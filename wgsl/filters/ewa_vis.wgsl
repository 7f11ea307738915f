// Filter `ewa_vis` (Romanyuk & Dudnyk 2017 (filtering with parallax mapping), full method): EWA where every
// footprint texel is tested for visibility (the view ray towards its surface point traced with the technique's own
// search, visibility/traced.wgsl); the hidden ones get no weight (inherit 0), or their weight goes to their
// substitute, the texel their ray meets, when that lies outside the footprint (inherit 1; common/ewa.wgsl).
// Every texel of the raster walk is visited once, and a substitute inside the footprint is left to the walk, so
// no texel of the footprint is counted twice.
// #include "common/ewa.wgsl"

fn filter_texture(tex: texture_2d<f32>, fp: Footprint) -> vec4f {
    return ewa(tex, fp, true, false, filter_params.inherit != 0u);
}
