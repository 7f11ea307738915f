// Soft self-shadowing (common/shadow.wgsl): render.wgsl's light_visibility per light; the samples' fetches add up
// in shadow_fetches (the cost view shows them with the view ray's).
// #include "common/shadow.wgsl"

var<private> shadow_fetches: u32;

fn light_visibility(uv: vec2f, t: f32, l: vec3f, lod: f32) -> f32 {
    let s = shadow_soft(uv, l);
    shadow_fetches += s.fetches;
    return s.visibility;
}
