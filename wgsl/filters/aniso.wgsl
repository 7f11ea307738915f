// Filter `aniso`: hardware anisotropic filtering, textureSampleGrad on a sampler with max_anisotropy (the
// renderer makes it with linear min, mag and mipmap filters, as WebGPU requires). How many probes the driver
// takes is not observable; the texel count is the usual estimate, 8 per probe, probes = the footprint's
// eccentricity up to max_anisotropy.
// #include "common/ellipse.wgsl"

fn filter_texture(tex: texture_2d<f32>, fp: Footprint) -> vec4f {
    let f = sanitized(fp);
    let size = vec2f(textureDimensions(tex, 0));
    let axes = footprint_axes(texture_bounded(f.dx, size) * size, texture_bounded(f.dy, size) * size);
    let most = f32(clamp(filter_params.max_anisotropy, MAX_ANISOTROPY_MIN, MAX_ANISOTROPY_MAX));
    let probes = clamp(ceil(axes.major / max(axes.minor, 1e-8)), 1.0, most);
    filter_stats.texels += 8u * u32(probes);
    return textureSampleGrad(tex, filter_sampler, f.uv, f.dx, f.dy);
}
