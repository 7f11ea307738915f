// Filter `nearest`: the texel the hit falls in, at level 0 (the sampler filters nothing).
// #include "common/footprint.wgsl"

fn filter_texture(tex: texture_2d<f32>, fp: Footprint) -> vec4f {
    filter_stats.texels += 1u;
    return textureSampleLevel(tex, filter_sampler, sanitized(fp).uv, 0.0);
}
