// The viewer's present copy (wgpuviewer/viewer/window.py): where a window's surface cannot be read back (OpenGL
// surfaces offer no COPY_SRC), the viewer draws each frame into a texture of its own and this fullscreen pass
// copies it, texel for texel, onto the surface's texture.
// #include "common/fullscreen.wgsl"

@group(0) @binding(0) var frame: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) pos: vec4f) -> @location(0) vec4f {
    return textureLoad(frame, vec2i(pos.xy), 0);
}
