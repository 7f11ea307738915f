// Complexity map (the adaptive-POM thesis, complexity_calculator.py) in three passes:
//   sobel_mag:       Sobel (ksize 3 or 5) -> magnitude; global max via atomicMax on the f32 bits (mag >= 0)
//   dilate_h:        horizontal max over +-radius (the repeated 3x3 dilation is a (2r+1)^2 box max)
//   dilate_v_finish: vertical max, / max, gamma, quantise to `levels`, 8-bit by truncation (stored as f32)
// Dividing after the max equals the listing's divide-then-dilate: rounded division is monotonic.
// #include "common/sobel.wgsl"

@group(0) @binding(3) var<storage, read_write> maxbits: atomic<u32>;

@compute @workgroup_size(8, 8)
fn sobel_mag(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height) { return; }
    let x = i32(gid.x);
    let y = i32(gid.y);
    var gx: f32;
    var gy: f32;
    if (P.ksize == 3u) {
        let g = sobel3(x, y);
        gx = g.x;
        gy = g.y;
    } else {
        // 5x5: smoothing [1 4 6 4 1], derivative [-1 -2 0 2 1], separable (row pass, then column pass).
        var rx: array<f32, 5>;  // per row offset: derivative along x
        var ry: array<f32, 5>;  // per row offset: smoothing along x
        for (var j = -2; j <= 2; j++) {
            let a = h(x - 2, y + j);
            let b = h(x - 1, y + j);
            let c = h(x, y + j);
            let d = h(x + 1, y + j);
            let e = h(x + 2, y + j);
            rx[j + 2] = (d - b) * 2.0 + (e - a);
            ry[j + 2] = c * 6.0 + (b + d) * 4.0 + (a + e);
        }
        gx = rx[2] * 6.0 + (rx[1] + rx[3]) * 4.0 + (rx[0] + rx[4]);
        gy = (ry[3] - ry[1]) * 2.0 + (ry[4] - ry[0]);
    }
    let m = sqrt(gx * gx + gy * gy);
    dst[gid.y * P.width + gid.x] = m;
    atomicMax(&maxbits, bitcast<u32>(m));
}

fn dilate_index(p: i32, n: i32) -> i32 {
    if (P.wrap_dilate == 1u) { return wrap_index(p, n); }
    return clamp(p, 0, n - 1);  // clamping repeats an edge texel: same max as ignoring the outside
}

@compute @workgroup_size(8, 8)
fn dilate_h(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height) { return; }
    let w = i32(P.width);
    let r = i32(min(P.radius, 1024u));
    let row = gid.y * P.width;
    var m = src[row + gid.x];
    for (var k = -r; k <= r; k++) {
        m = max(m, src[row + u32(dilate_index(i32(gid.x) + k, w))]);
    }
    dst[row + gid.x] = m;
}

@compute @workgroup_size(8, 8)
fn dilate_v_finish(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height) { return; }
    let hh = i32(P.height);
    let r = i32(min(P.radius, 1024u));
    var m = src[gid.y * P.width + gid.x];
    for (var k = -r; k <= r; k++) {
        m = max(m, src[u32(dilate_index(i32(gid.y) + k, hh)) * P.width + gid.x]);
    }
    let mx = bitcast<f32>(atomicLoad(&maxbits));
    var c = 0.0;
    if (mx > 0.0) {
        c = clamp(m / mx, 0.0, 1.0);
        if (c > 0.0) { c = pow(c, P.gamma); }
    }
    let q = round(c / P.step) * P.step;
    dst[gid.y * P.width + gid.x] = floor(q * 255.0);
}
