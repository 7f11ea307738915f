// What every technique shares: the trace result, the fetch counter, the view-ray span.
// The generated interface (wgpuviewer/relief/shaders.py) declares TraceParams, the constants and the bindings.
//
// Convention (design.md): tangent space x = u, y = v, z = normal; the relief lies below z = 0;
// the depth texture holds D = 1 - height; V points from the surface towards the eye.
// A ray entering at uv0 reaches uv(t) = uv0 - t * (V.xy / V.z) * height_scale at layer depth t.

// V.z below this is grazing or back-facing: the ray span is clamped (finite) and the result flagged.
const MIN_VIEW_Z: f32 = 1e-4;

struct TraceResult {
    uv: vec2f,      // where the ray meets the relief (not wrapped)
    depth: f32,     // layer depth t of that point, 0 = top
    fetches: u32,   // depth-map fetches spent
    capped: bool,   // a cap or clamp decided the result: do not trust it
    layers: u32,    // depth layers (linear steps) the search used; 0 for techniques without layers
}

// Counted so every technique reports its cost the same way.
var<private> fetch_count: u32;

fn is_grazing(v: vec3f) -> bool {
    return v.z < MIN_VIEW_Z;
}

// UV distance the ray travels from t = 0 to t = 1; finite for any v.
fn parallax_span(v: vec3f) -> vec2f {
    return v.xy / max(v.z, MIN_VIEW_Z) * trace_params.height_scale;
}

fn untraced(uv: vec2f) -> TraceResult {
    return TraceResult(uv, 0.0, 0u, false, 0u);
}
