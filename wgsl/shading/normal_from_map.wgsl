// Shading normal from the normal map (rgba8unorm, n * 0.5 + 0.5, tangent frame x = u, y = v).
fn shading_normal(uv: vec2f, duv_dx: vec2f, duv_dy: vec2f) -> vec3f {
    let n = textureSampleGrad(normal_tex, material_sampler, uv, duv_dx, duv_dy).xyz * 2.0 - 1.0;
    return normalize(n);
}
