// The viewer's render scale (wgpuviewer/viewer/render_scale.py): the scene, drawn into a texture a fraction of the
// window's size, is stretched over the window with bilinear filtering; the HUD is drawn over it at full resolution.
// Upscale is generated from render_scale.py's UPSCALE.
// #include "common/fullscreen.wgsl"

@group(0) @binding(0) var scene_frame: texture_2d<f32>;
@group(0) @binding(1) var scene_sampler: sampler;
@group(0) @binding(2) var<uniform> upscale: Upscale;

@fragment
fn fs_main(@builtin(position) pos: vec4f) -> @location(0) vec4f {
    return textureSampleLevel(scene_frame, scene_sampler, pos.xy / upscale.target_size.xy, 0.0);
}
