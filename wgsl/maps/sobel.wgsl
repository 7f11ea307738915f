// Sobel 3x3 gradient (x: along columns/u, y: along rows) of the map the including kernel reads with h(x, y).
// Same operation grouping as OpenCV's separable Sobel, centre*2 + (side + side), so results are bit-exact.
fn sobel3(x: i32, y: i32) -> vec2f {
    let dm = h(x + 1, y - 1) - h(x - 1, y - 1);
    let d0 = h(x + 1, y) - h(x - 1, y);
    let dp = h(x + 1, y + 1) - h(x - 1, y + 1);
    let sm = h(x, y - 1) * 2.0 + (h(x - 1, y - 1) + h(x + 1, y - 1));
    let sp = h(x, y + 1) * 2.0 + (h(x - 1, y + 1) + h(x + 1, y + 1));
    return vec2f(d0 * 2.0 + (dm + dp), sp - sm);
}
