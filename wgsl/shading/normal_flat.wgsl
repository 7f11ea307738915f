// Shading normal of a flat surface (techniques without a normal map).
fn shading_normal(fp: Footprint) -> vec3f {
    return vec3f(0.0, 0.0, 1.0);
}
