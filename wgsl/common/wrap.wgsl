// Repeat addressing for textureLoad: a texel index brought into [0, size) (tiling textures).
// Float floor division instead of integer `%` (twice, for negative indices): exact for |texel| < 2^24, and
// integer division has no SIMD instruction on CPUs (llvmpipe runs it lane by lane) and is a long emulated
// sequence on GPUs. The clamp only guards indices beyond that range.
fn wrap_texel(texel: vec2i, size: vec2i) -> vec2i {
    let k = vec2i(floor(vec2f(texel) / vec2f(size)));
    return clamp(texel - k * size, vec2i(0), size - 1);
}
