// Filter `trilinear` (the default): the hardware picks the level from the larger derivative and blends two
// levels bilinearly. With the `uv` derivative source: the plain hardware lookup of the unperturbed footprint.
// #include "common/footprint.wgsl"

fn filter_texture(tex: texture_2d<f32>, fp: Footprint) -> vec4f {
    let f = sanitized(fp);
    filter_stats.texels += 8u;
    return textureSampleGrad(tex, filter_sampler, f.uv, f.dx, f.dy);
}
