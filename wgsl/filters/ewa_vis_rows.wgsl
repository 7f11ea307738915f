// Filter `ewa_vis_rows` (Romanyuk & Dudnyk 2017 (filtering with parallax mapping), cheap method): EWA where each
// row of the ellipse is walked from its left end until the first hidden texel, then from its right end back until
// the next hidden texel; the texels between are dropped without being traced (the paper assumes a row's hidden
// texels are one run). With inherit 1 the two traced hidden texels of a row pass their weight to their
// substitutes as in ewa_vis; the untraced ones between have none and stay dropped.
// #include "common/ewa.wgsl"

fn filter_texture(tex: texture_2d<f32>, fp: Footprint) -> vec4f {
    return ewa(tex, fp, true, true, filter_params.inherit != 0u);
}
