// Normal map from a height map: Sobel 3x3 gradients, unit normals, three f32 per texel.
// n = normalize(-s * dH/du, ysign * s * dH/drow, 1), dH/d* = Sobel / 8 (height units per texel).
// ysign = +1 for the OpenGL convention (y towards row 0, "green up"), -1 for DirectX (y towards +row).
// #include "common/sobel.wgsl"

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height) { return; }
    let g = sobel3(i32(gid.x), i32(gid.y));
    let n = normalize(vec3f(-P.strength * g.x * 0.125, P.ysign * P.strength * g.y * 0.125, 1.0));
    let i = (gid.y * P.width + gid.x) * 3u;
    dst[i] = n.x;
    dst[i + 1u] = n.y;
    dst[i + 2u] = n.z;
}
