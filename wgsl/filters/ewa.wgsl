// Filter `ewa`: the elliptical weighted average of common/ewa.wgsl over every texel of the footprint.
// #include "common/ewa.wgsl"

fn filter_texture(tex: texture_2d<f32>, fp: Footprint) -> vec4f {
    return ewa(tex, fp, false, false, false);
}
