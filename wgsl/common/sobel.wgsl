// Sobel 3x3 gradient (x: along columns/u, y: along rows) of the source map (normal and complexity kernels;
// their Params have width, height and border). Same operation grouping as OpenCV's separable Sobel,
// centre*2 + (side + side), so results are bit-exact.
// #include "common/map_buffers.wgsl"

// The source map at (x, y), outside the map by the kernel's border mode.
fn h(x: i32, y: i32) -> f32 {
    let w = i32(P.width);
    let hh = i32(P.height);
    return src[border_index(y, hh, P.border) * w + border_index(x, w, P.border)];
}

fn sobel3(x: i32, y: i32) -> vec2f {
    let dm = h(x + 1, y - 1) - h(x - 1, y - 1);
    let d0 = h(x + 1, y) - h(x - 1, y);
    let dp = h(x + 1, y + 1) - h(x - 1, y + 1);
    let sm = h(x, y - 1) * 2.0 + (h(x - 1, y - 1) + h(x + 1, y - 1));
    let sp = h(x, y + 1) * 2.0 + (h(x - 1, y + 1) + h(x + 1, y + 1));
    return vec2f(d0 * 2.0 + (dm + dp), sp - sm);
}
