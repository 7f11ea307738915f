// Basic texturing: the surface is taken as flat, so the ray meets it where it enters.
// #include "common/trace.wgsl"

fn trace(uv: vec2f, v: vec3f, lod: f32) -> TraceResult {
    return untraced(uv);
}
