// Depth fetches, counted (fetch_count). Explicit level: ray-march loops are non-uniform control flow, where
// textureSample is not allowed.
// #include "common/trace.wgsl"

fn depth_at(uv: vec2f, lod: f32) -> f32 {
    fetch_count += 1u;
    return textureSampleLevel(depth_tex, material_sampler, uv, lod).r;
}
