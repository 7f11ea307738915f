// Filter `ewa_approx`: EWA approximated by hardware trilinear probes along the major axis of the footprint
// ellipse, in the spirit of Mavridis & Papaioannou 2011. probes = ceil(major / minor) up to max_probes, spread
// evenly over the major diameter at s = (2k + 1 - n) / n semi-axes, weighted exp(-alpha s^2) - exp(-alpha) like
// EWA's Gaussian; each probe at the level of the minor semi-axis, widened to major / probes when the probes
// cannot cover the major axis.
// #include "common/ellipse.wgsl"

fn filter_texture(tex: texture_2d<f32>, footprint: Footprint) -> vec4f {
    let size = vec2f(textureDimensions(tex, 0));
    let fp = loop_footprint(footprint, size);
    let axes = footprint_axes(fp.dx * size, fp.dy * size);
    let most = f32(clamp(filter_params.max_probes, MAX_PROBES_MIN, MAX_PROBES_MAX));
    let n = clamp(ceil(axes.major / max(axes.minor, 1e-8)), 1.0, most);
    let lod = log2(max(max(axes.minor, axes.major / n), 1e-8));
    let semi = axes.dir * axes.major / size;  // the major semi-axis in uv
    let alpha = clamp(filter_params.alpha, ALPHA_MIN, ALPHA_MAX);
    var value = vec4f(0.0);
    var weight = 0.0;
    for (var k = 0u; k < u32(n) && k < MAX_PROBES_MAX; k++) {
        let s = (2.0 * f32(k) + 1.0 - n) / n;
        let w = exp(-alpha * s * s) - exp(-alpha);
        value += w * textureSampleLevel(tex, filter_sampler, fp.uv + s * semi, lod);
        weight += w;
    }
    filter_stats.texels += 8u * u32(n);
    return value / weight;
}
