// Filter `ewa_vis` (Romanyuk & Dudnyk 2017 (filtering with parallax mapping), full method): EWA where every
// footprint texel is tested for visibility (the view ray towards its surface point traced with the technique's own
// search, visibility/traced.wgsl) and the hidden ones get no weight. Every texel of the raster walk is visited
// once, so none can be counted twice.
// #include "common/ewa.wgsl"

fn filter_texture(tex: texture_2d<f32>, fp: Footprint) -> vec4f {
    return ewa(tex, fp, true, false);
}
