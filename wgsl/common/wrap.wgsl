// Repeat addressing for textureLoad: a texel index brought into [0, size) (tiling textures).
fn wrap_texel(texel: vec2i, size: vec2i) -> vec2i {
    return ((texel % size) + size) % size;
}
