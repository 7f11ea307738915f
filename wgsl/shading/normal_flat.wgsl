// Shading normal of a flat surface (techniques without a normal map).
fn shading_normal(uv: vec2f, duv_dx: vec2f, duv_dy: vec2f) -> vec3f {
    return vec3f(0.0, 0.0, 1.0);
}
