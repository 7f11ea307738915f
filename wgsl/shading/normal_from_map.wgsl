// Shading normal from the normal map (rgba8unorm, n * 0.5 + 0.5, tangent frame x = u, y = v), read through the
// draw's texture filter over the same footprint as the albedo.
fn shading_normal(fp: Footprint) -> vec3f {
    let n = filter_texture(normal_tex, fp).xyz * 2.0 - 1.0;
    return normalize(n);
}
