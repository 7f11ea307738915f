// Map kernels (maptools): row-major f32 buffers, index = row * width + col; col = u (x), row = v (y).
// The kernel's Params struct (generated: maptools.gpu.PARAMS) is its uniform P; it reads src and writes dst.
// #include "common/border.wgsl"

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> src: array<f32>;
@group(0) @binding(2) var<storage, read_write> dst: array<f32>;
