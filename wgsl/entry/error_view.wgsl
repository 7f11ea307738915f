// The viewer's error view (wgpuviewer/viewer/error_view.py): an r32float texture of per-pixel values painted
// over part of the frame with the cost view's heat ramp; negative values keep the frame underneath.
// Blit is generated from wgpuviewer/viewer/error_view.py (BLIT).
// #include "common/heat.wgsl"
// #include "common/fullscreen.wgsl"

@group(0) @binding(0) var<uniform> blit: Blit;
@group(0) @binding(1) var values: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) pos: vec4f) -> @location(0) vec4f {
    let size = vec2f(textureDimensions(values));
    let frame = vec2f(blit.rect.z, blit.rect.w);
    let texel = vec2i(clamp((pos.xy - blit.rect.xy) / frame * size, vec2f(0.0), size - 1.0));
    let value = textureLoad(values, texel, 0).r;
    if value < 0.0 {
        discard;  // nothing drawn there
    }
    return vec4f(heat(value / blit.max_value), 1.0);
}
