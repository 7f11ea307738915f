// Every method of the perspective study as a compute kernel, each the twin of its numpy form in
// wgpuviewer/studies/perspective/methods.py (same operations in the same order; a test pins them bit for bit),
// except the adaptive subdivision (a CPU loop only: wgpuviewer/studies/perspective/compiled.py).
// Per-pixel methods run one thread per pixel (x: pixel in the span, y: span); the others one thread per span
// (incremental and its mitigations), k threads per span (parallel), two (two_ended) or one per subdivision
// (subdivided), numbered along x. Every loop is capped.
// #include "studies/perspective/common.wgsl"

// The forms of one kernel shape share an entry point; the pipeline-overridable FORM (kernels.py sets it per
// method, with the FORM_* constants it generates) picks the form when the pipeline is created, so each form
// compiles on its own, without a branch per pixel.
override FORM: u32 = FORM_DIRECT;

// One thread per pixel: formula (1) (direct), or formula (3) from the constants span_setup wrote (span); each
// with two divisions or with one reciprocal (_rcp).
@compute @workgroup_size(64)
fn per_pixel(@builtin(global_invocation_id) gid: vec3u) {
    let n = gid.x;
    let s = gid.y;
    if n >= P.span_length || s >= P.span_count {
        return;
    }
    switch FORM {
        case FORM_SPAN: { store(s, n, starts[s].xyz + P.a * f32(n)); }
        case FORM_SPAN_RCP: { store_rcp(s, n, starts[s].xyz + P.a * f32(n)); }
        case FORM_DIRECT_RCP: { store_rcp(s, n, linear(f32(spans[s].x0 + i32(n)), f32(spans[s].y))); }
        default: { store(s, n, linear(f32(spans[s].x0 + i32(n)), f32(spans[s].y))); }
    }
}

// One thread per span: the per-span constants for `span`.
@compute @workgroup_size(64)
fn span_setup(@builtin(global_invocation_id) gid: vec3u) {
    let s = gid.x;
    if s < P.span_count {
        starts[s] = vec4f(span_start(s), 0.0);
    }
}

// One thread per span walks it from n = 0: formula (4) (incremental) and its mitigations.
@compute @workgroup_size(64)
fn sequential(@builtin(global_invocation_id) gid: vec3u) {
    let s = gid.x;
    if s >= P.span_count {
        return;
    }
    switch FORM {
        case FORM_REANCHOR: { reanchor(s); }
        case FORM_KAHAN: { kahan(s); }
        case FORM_DOUBLE_SINGLE: { double_single(s); }
        case FORM_FIXED16_16: { fixed16_16(s); }
        default: { incremental(s); }
    }
}

// Formula (4).
fn incremental(s: u32) {
    var w = span_start(s);
    for (var n = 0u; n < span_len(); n++) {
        store(s, n, w);
        w = w + P.a;
    }
}

// k = P.param threads per span: formula (5). Thread j gets w_j by j steps of (4), then steps k * a. A span shorter
// than k gets one thread per pixel (as many as kernels.py dispatches: Method.threads_per_span), none striding.
@compute @workgroup_size(64)
fn parallel(@builtin(global_invocation_id) gid: vec3u) {
    let k = clamp(min(P.param, span_len()), 1u, MAX_THREADS);
    let t = gid.x;
    let s = t / k;
    let j = t % k;
    if s >= P.span_count || j >= span_len() {
        return;
    }
    var w = span_start(s);
    for (var i = 0u; i < j; i++) {
        w = w + P.a;
    }
    let stride = P.a * f32(k);
    for (var r = 0u; r < MAX_SPAN; r++) {
        let n = j + r * k;
        if n >= span_len() {
            break;
        }
        store(s, n, w);
        w = w + stride;
    }
}

// Two threads per span: one walks up from n = 0, the other down from n = L - 1 (started by the span form),
// in one loop without branches (w + (-a) is w - a exactly). The first span_count threads walk up, the rest down.
@compute @workgroup_size(64)
fn two_ended(@builtin(global_invocation_id) gid: vec3u) {
    let t = gid.x;
    if t >= 2u * P.span_count {
        return;
    }
    let s = t % P.span_count;
    let down = t >= P.span_count;
    let len = span_len();
    let half = (len + 1u) / 2u;
    let start = span_start(s);
    var w = select(start, start + P.a * f32(len - 1u), down);
    let step = select(P.a, -P.a, down);
    let count = select(half, len - half, down);
    for (var r = 0u; r < count; r++) {
        store(s, select(r, len - 1u - r, down), w);
        w = w + step;
    }
}

struct Anchor {
    uv: vec2f,  // 0 where flagged
    flagged: bool,
}

fn anchor(s: u32, start: vec3f, n: u32) -> Anchor {
    let w = start + P.a * f32(n);
    let flagged = !is_defined(w) || clipped(s, n);
    return Anchor(select(w.xy / w.z, vec2f(0.0), flagged), flagged);
}

// One thread per subdivision of S = P.param pixels: exact at both ends (span form), linear in between; the
// last subdivision ends at the span's last pixel and writes it too.
@compute @workgroup_size(64)
fn subdivided(@builtin(global_invocation_id) gid: vec3u) {
    let every = clamp(P.param, 1u, MAX_SPAN);
    let len = span_len();
    let parts = max((len - 1u + every - 1u) / every, 1u);
    let t = gid.x;
    let s = t / parts;
    if s >= P.span_count {
        return;
    }
    let start = span_start(s);
    let a = (t % parts) * every;
    let first = anchor(s, start, a);
    if len == 1u {
        store_uv(s, 0u, first.uv, first.flagged);
        return;
    }
    let b = min(a + every, len - 1u);
    let last = anchor(s, start, b);
    let slope = (last.uv - first.uv) / f32(b - a);
    let flagged = first.flagged || last.flagged;
    for (var m = 0u; m < min(b - a, MAX_SPAN); m++) {
        store_uv(s, a + m, first.uv + f32(m) * slope, flagged);
    }
    if b == len - 1u {
        store_uv(s, b, last.uv, last.flagged);
    }
}

// Formula (4), with the span form afresh every M = P.param pixels.
fn reanchor(s: u32) {
    let every = max(P.param, 1u);
    let start = span_start(s);
    var w = start;
    for (var n = 0u; n < span_len(); n++) {
        if n % every == 0u {
            w = start + P.a * f32(n);
        }
        store(s, n, w);
        w = w + P.a;
    }
}

// Formula (4) with Kahan-compensated sums.
fn kahan(s: u32) {
    var sum = span_start(s);
    var comp = vec3f(0.0);
    for (var n = 0u; n < span_len(); n++) {
        store(s, n, sum);
        let y = P.a - comp;
        let t = sum + y;
        comp = (t * P.one - sum) - y;
        sum = t;
    }
}

// Formula (4) with a two-float accumulator (hi, lo) and increment (a, a_lo).
fn double_single(s: u32) {
    var hi = span_start(s);
    var lo = vec3f(0.0);
    for (var n = 0u; n < span_len(); n++) {
        store(s, n, hi + lo);
        let sum = (hi + P.a) * P.one;
        let bb = (sum - hi) * P.one;
        let err = (hi - (sum - bb)) + (P.a - bb);
        let e = err + (lo + P.a_lo);
        hi = (sum + e) * P.one;
        lo = e - (hi - sum);
    }
}

// Formula (4) in int32 16.16 fixed point (wrapping adds, as the numpy twin's int32 sums).
fn fixed16_16(s: u32) {
    var w = spans[s].fixed_start;
    for (var n = 0u; n < span_len(); n++) {
        let f = vec3f(w);
        let uv = vec2f((f.x / f.z) * P.fixed_ratio.x, (f.y / f.z) * P.fixed_ratio.y);
        store_uv(s, n, uv, !(f.z > 0.0 && abs(uv.x) <= UMAX && abs(uv.y) <= UMAX) || clipped(s, n));
        w = w + P.fixed_step;
    }
}
