// The perspective study's kernel interface (wgpuviewer/studies/perspective/kernels.py declares and packs its
// records): the polygon's coefficients as three columns over the quantities (w_u, w_v, q), the spans, the
// outputs, and what every method shares: the per-span constants and the flagged store.
// Pixel (x0 + n, y) of a span: w = a * x + b * y + c componentwise; u = w.x / w.z, v = w.y / w.z (texels).

// |u| or |v| beyond this has no fractional bits left in f32: the pixel is flagged (geometry.UMAX).
const UMAX: f32 = 16777216.0;
// Hard caps of every loop: the longest span (geometry.MAX_SPAN) and the most threads per span.
const MAX_SPAN: u32 = 16384u;
const MAX_THREADS: u32 = 32u;

// Params (P) and Span are generated into the module from kernels.py's PARAMS and SPAN (core.structs).

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> spans: array<Span>;
@group(0) @binding(2) var<storage, read_write> starts: array<vec4f>;  // per-span constants (span_setup)
@group(0) @binding(3) var<storage, read_write> out_uv: array<vec2f>;
@group(0) @binding(4) var<storage, read_write> out_flags: array<u32>;

fn span_len() -> u32 {
    return min(P.span_length, MAX_SPAN);
}

// a * x + b * y + c, in that order: the opaque factor P.one keeps the compiler from reassociating the sum.
fn linear(x: f32, y: f32) -> vec3f {
    return (P.a * x + P.b * y) * P.one + P.c;
}

// ut_u, ut_v, ub: the per-span constants a * x0 + b * y + c.
fn span_start(s: u32) -> vec3f {
    return linear(f32(spans[s].x0), f32(spans[s].y));
}

fn is_defined(w: vec3f) -> bool {
    return w.z > 0.0 && abs(w.x) <= UMAX * w.z && abs(w.y) <= UMAX * w.z;
}

fn clipped(s: u32, n: u32) -> bool {
    return i32(n) < spans[s].defined.x || i32(n) >= spans[s].defined.y;
}

fn store_uv(s: u32, n: u32, uv: vec2f, flagged: bool) {
    let i = s * P.span_length + n;
    out_uv[i] = select(uv, vec2f(0.0), flagged);
    out_flags[i] = select(0u, 1u, flagged);
}

// Pixel n of span s from its (w_u, w_v, q): the division, or 0 and a flag where the texel is not defined.
fn store(s: u32, n: u32, w: vec3f) {
    store_uv(s, n, vec2f(w.x / w.z, w.y / w.z), !is_defined(w) || clipped(s, n));
}

// The same with one division: r = 1 / q, then two multiplications.
fn store_rcp(s: u32, n: u32, w: vec3f) {
    let r = 1.0 / w.z;
    store_uv(s, n, vec2f(w.x * r, w.y * r), !is_defined(w) || clipped(s, n));
}
