// Border handling of the map kernels (OpenCV's border modes; maptools/cpu.py is the CPU twin).

const BORDER_REPEAT: u32 = 0u;   // wrap (tiling textures)
const BORDER_CLAMP: u32 = 1u;    // replicate the edge texel (OpenCV BORDER_REPLICATE)
const BORDER_REFLECT: u32 = 2u;  // reflect-101, OpenCV's default (BORDER_REFLECT_101)

// p mod n in [0, n) using only non-negative operands (`%` of negatives differs between backends, e.g. GL).
fn wrap_index(p: i32, n: i32) -> i32 {
    if (p >= 0) { return p % n; }
    return n - 1 - ((-p - 1) % n);
}

// Index p (possibly outside [0, n)) mapped into [0, n) the way OpenCV's borderInterpolate does.
fn border_index(p: i32, n: i32, mode: u32) -> i32 {
    if (p >= 0 && p < n) { return p; }
    if (mode == BORDER_REPEAT) { return wrap_index(p, n); }
    if (mode == BORDER_CLAMP || n == 1) { return clamp(p, 0, n - 1); }
    var q = p;
    for (var k = 0; k < 16; k++) {   // bounded: offsets are at most a few texels
        if (q < 0) { q = -q; } else if (q >= n) { q = 2 * n - 2 - q; } else { break; }
    }
    return clamp(q, 0, n - 1);
}
