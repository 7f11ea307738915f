// Filter `bilinear`: the sampler's bilinear blend of four texels at level 0, derivatives ignored.
// #include "common/footprint.wgsl"

fn filter_texture(tex: texture_2d<f32>, fp: Footprint) -> vec4f {
    filter_stats.texels += 4u;
    return textureSampleLevel(tex, filter_sampler, sanitized(fp).uv, 0.0);
}
