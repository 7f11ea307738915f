// Filter `ewa_vis_rows` (Romanyuk & Dudnyk 2017 (filtering with parallax mapping), cheap method): EWA where each
// row of the ellipse is walked from its left end until the first hidden texel, then from its right end back until
// the next hidden texel; the texels between are dropped without being traced (the paper assumes a row's hidden
// texels are one run).
// #include "common/ewa.wgsl"

fn filter_texture(tex: texture_2d<f32>, fp: Footprint) -> vec4f {
    return ewa(tex, fp, true, true);
}
