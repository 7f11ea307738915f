// Shadows off: every light reaches every point (no shadow code is compiled; render.wgsl's light_visibility).
// #include "common/trace.wgsl"

var<private> shadow_fetches: u32;

fn light_visibility(uv: vec2f, t: f32, l: vec3f, lod: f32) -> f32 {
    return 1.0;
}
