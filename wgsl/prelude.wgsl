// Shared by every technique, the render entry points (render.wgsl) and the probe (probe.wgsl).
// `struct TraceParams` is generated from wgpuviewer/techniques.py (TRACE_FIELDS) and prepended.
//
// Convention (design.md): tangent space x = u, y = v, z = normal; the relief lies below z = 0;
// the depth texture holds D = 1 - height; V points from the surface towards the eye.
// A ray entering at uv0 reaches uv(t) = uv0 - t * (V.xy / V.z) * height_scale at layer depth t.

// Hard cap on any layer count (mirrors techniques.MAX_LAYERS).
const MAX_LAYERS: u32 = 1024u;
// V.z below this is grazing or back-facing: the ray span is clamped (finite) and the result flagged.
const MIN_VIEW_Z: f32 = 1e-4;

struct TraceResult {
    uv: vec2f,      // where the ray meets the relief (not wrapped)
    depth: f32,     // layer depth t of that point, 0 = top
    fetches: u32,   // depth-map fetches spent
    capped: bool,   // a cap or clamp decided the result: do not trust it
    layers: u32,    // depth layers (linear steps) the search used; 0 for techniques without layers
}

@group(1) @binding(0) var<uniform> trace_params: TraceParams;
@group(1) @binding(1) var material_sampler: sampler;
@group(1) @binding(2) var albedo_tex: texture_2d<f32>;
@group(1) @binding(3) var normal_tex: texture_2d<f32>;
@group(1) @binding(4) var depth_tex: texture_2d<f32>;
// Maps derived from the depth map (wgpuviewer/maps.py); bound only for techniques that need them.
@group(1) @binding(5) var complexity_tex: texture_2d<f32>;
// Max pyramid atlas (maxmip.wgsl): r32float, level m at rows [row_m, row_m + h_m), read with textureLoad.
@group(1) @binding(6) var maxmip_tex: texture_2d<f32>;
// Distance volume (distance.wgsl): r32float (W, H, slices), plain or visibility-refined, textureLoad.
@group(1) @binding(7) var distance_tex: texture_3d<f32>;
// Relaxed cone map (cone.wgsl): r32float (W, H) cone ratios, texels of u per unit t, textureLoad.
@group(1) @binding(8) var cone_tex: texture_2d<f32>;

// Counted so every technique reports its cost the same way.
var<private> fetch_count: u32;

// Explicit level: ray-march loops are non-uniform control flow, where textureSample is not allowed.
fn depth_at(uv: vec2f, lod: f32) -> f32 {
    fetch_count += 1u;
    return textureSampleLevel(depth_tex, material_sampler, uv, lod).r;
}

fn is_grazing(v: vec3f) -> bool {
    return v.z < MIN_VIEW_Z;
}

// UV distance the ray travels from t = 0 to t = 1; finite for any v.
fn parallax_span(v: vec3f) -> vec2f {
    return v.xy / max(v.z, MIN_VIEW_Z) * trace_params.height_scale;
}

fn layer_count() -> u32 {
    return u32(clamp(trace_params.layers, 1.0, f32(MAX_LAYERS)));
}

fn untraced(uv: vec2f) -> TraceResult {
    return TraceResult(uv, 0.0, 0u, false, 0u);
}

// The steep-parallax loop: step through n equal depth layers until the first layer below the surface.
// Bounded by n <= MAX_LAYERS: at layer n the ray is at t = 1, below any depth, so the thesis' open-ended
// while loop always ends there anyway.
struct LayerMarch {
    uv: vec2f,          // where the march stopped
    duv: vec2f,         // uv step per layer
    layers: u32,        // layers stepped (0: the entry point is already on the surface)
    layer_step: f32,    // 1 / n
    d: f32,             // depth at uv
    d_prev: f32,        // depth one layer earlier (kept instead of fetched again)
}

fn layer_march(uv0: vec2f, v: vec3f, lod: f32, n: u32) -> LayerMarch {
    let layer_step = 1.0 / f32(n);
    let duv = parallax_span(v) * layer_step;
    var uv = uv0;
    var d = depth_at(uv, lod);
    var d_prev = d;
    var i = 0u;
    while i < n && f32(i) * layer_step < d {
        i += 1u;
        uv -= duv;
        d_prev = d;
        d = depth_at(uv, lod);
    }
    return LayerMarch(uv, duv, i, layer_step, d, d_prev);
}

// The POM search shared by pom and pom_adaptive: the layer march, then linear interpolation between the
// last layer above the surface and the first one below it (the thesis fetches the previous sample twice;
// the march keeps it).
fn pom_search(uv0: vec2f, v: vec3f, lod: f32, n: u32) -> TraceResult {
    let m = layer_march(uv0, v, lod, n);
    if m.layers == 0u {
        return TraceResult(uv0, 0.0, fetch_count, is_grazing(v), n);
    }
    let layer = f32(m.layers) * m.layer_step;
    let after = m.d - layer;                            // <= 0: this sample is below the surface
    let before = m.d_prev - (layer - m.layer_step);     // > 0: the previous one was above it
    let denom = after - before;
    // denom < 0 whenever the bracket is real; guard the degenerate case instead of dividing by 0.
    let w = select(0.0, clamp(after / denom, 0.0, 1.0), denom < -1e-12);
    return TraceResult(m.uv + m.duv * w, layer - w * m.layer_step, fetch_count, is_grazing(v), n);
}

// Smallest s in [0, len] with a s^2 + b s + c = 0 given c < 0 (f = t - D below zero at s = 0), or -1.
// Cancellation-free pair q/a, c/q; a == 0 (linear) falls out as -c/b. Roots a rounding error past the
// interval are accepted (clamped): the caller's next cell would catch them at its entry anyway.
fn first_root(a: f32, b: f32, c: f32, len: f32) -> f32 {
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return -1.0;
    }
    let q = -0.5 * (b + select(-1.0, 1.0, b >= 0.0) * sqrt(disc));
    let slack = 1e-6 * max(len, 1.0);
    var best = 3.0e38;
    if a != 0.0 {
        let r = q / a;
        if r >= -slack && r <= len + slack { best = min(best, r); }
    }
    if q != 0.0 {
        let r = c / q;
        if r >= -slack && r <= len + slack { best = min(best, r); }
    }
    if best > 2.0e38 {
        return -1.0;
    }
    return clamp(best, 0.0, len);
}

// The exact first hit inside one bilinear cell (between texel centres cell and cell + 1, texel
// coordinates x = u * W - 0.5), for the ray p(t) = start + t * dir over [t0, t1]: f(t) = t - D(p(t))
// is a quadratic there (as in wgpuviewer/reference.py). Returns t of the hit, or -1. The cell's four
// depths come from one textureGather (counted as one fetch), addressed by the material sampler.
fn cell_hit(cell: vec2i, start: vec2f, dir: vec2f, t0: f32, t1: f32) -> f32 {
    fetch_count += 1u;
    let size = vec2f(textureDimensions(depth_tex, 0));
    // Gather order: (umin, vmax), (umax, vmax), (umax, vmin), (umin, vmin).
    let g = textureGather(0, depth_tex, material_sampler, (vec2f(cell) + 1.0) / size);
    let c00 = g.w;
    let c10 = g.z;
    let c01 = g.x;
    let c11 = g.y;
    let bx = c10 - c00;
    let cy = c01 - c00;
    let exy = c11 - c10 - c01 + c00;
    let e = clamp(start + t0 * dir - vec2f(cell), vec2f(0.0), vec2f(1.0));
    let qc = t0 - (c00 + bx * e.x + cy * e.y + exy * e.x * e.y);
    if qc >= 0.0 {
        return t0;
    }
    let qb = 1.0 - (bx * dir.x + cy * dir.y + exy * (e.x * dir.y + e.y * dir.x));
    let qa = -exy * dir.x * dir.y;
    let s = first_root(qa, qb, qc, max(t1 - t0, 0.0));
    if s >= 0.0 {
        return t0 + s;
    }
    if t1 >= 1.0 {
        return 1.0;  // f(1) = 1 - D >= 0: a root lost to rounding at the floor of the relief
    }
    return -1.0;
}

