// Compute probe of whether the adapter honours textureSampleGrad's explicit gradients
// (wgpuviewer/relief/filter_probe.py, explicit_gradient_support): each sample reads the probe texture (level 0
// horizontal 1-texel stripes, every coarser level flat grey) at a given uv and gradient pair, through an isotropic
// trilinear sampler and through an anisotropic one (max_anisotropy 16). GradientSample and GradientValue are
// generated from GRADIENT_SAMPLE and GRADIENT_VALUE there.

@group(0) @binding(0) var<storage, read> samples: array<GradientSample>;
@group(0) @binding(1) var<storage, read_write> results: array<GradientValue>;
@group(1) @binding(0) var stripes: texture_2d<f32>;
@group(1) @binding(1) var isotropic_sampler: sampler;
@group(1) @binding(2) var anisotropic_sampler: sampler;

@compute @workgroup_size(64)
fn gradient_probe_main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    if i < arrayLength(&samples) {
        let s = samples[i];
        let iso = textureSampleGrad(stripes, isotropic_sampler, s.uv, s.ddx, s.ddy).r;
        let aniso = textureSampleGrad(stripes, anisotropic_sampler, s.uv, s.ddx, s.ddy).r;
        results[i] = GradientValue(iso, aniso);
    }
}
