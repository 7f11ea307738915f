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
}

@group(1) @binding(0) var<uniform> trace_params: TraceParams;
@group(1) @binding(1) var material_sampler: sampler;
@group(1) @binding(2) var albedo_tex: texture_2d<f32>;
@group(1) @binding(3) var normal_tex: texture_2d<f32>;
@group(1) @binding(4) var depth_tex: texture_2d<f32>;
// Maps derived from the depth map (wgpuviewer/maps.py); bound only for techniques that need them.
@group(1) @binding(5) var complexity_tex: texture_2d<f32>;

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
    return TraceResult(uv, 0.0, 0u, false);
}
