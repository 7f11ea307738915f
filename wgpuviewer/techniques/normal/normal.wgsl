// Normal mapping: no displacement; the relief shows only through the shading normal.
// #include "common/trace.wgsl"

fn trace(uv: vec2f, v: vec3f, lod: f32) -> TraceResult {
    return untraced(uv);
}
