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

// The ray's pixel on screen: uv per pixel along screen x (column 0) and y (column 1), set by the entry point before
// `trace` (render: the unperturbed uv's derivatives; probe: the ray's own, or none); zero where there is none. A
// screen-space error budget reads it (auto's max_error_px: zero falls back to the texel budget).
var<private> pixel_footprint: mat2x2f;

fn is_grazing(v: vec3f) -> bool {
    return v.z < MIN_VIEW_Z;
}

// UV distance the ray travels from t = 0 to t = 1; finite for any v.
fn parallax_span(v: vec3f) -> vec2f {
    return v.xy / max(v.z, MIN_VIEW_Z) * trace_params.height_scale;
}

// The depth interval a search along the ray needs, from t0 on: [max(t0, depth_min), depth_max], the depth map's
// range (the renderer and the probe pass the uploaded map's lowest and highest depth, widened by the filtering
// slack, maps.depth_range). Above depth_min the ray is above every point of the surface and at depth_max it is at
// or below all of them, so a layer outside the range can only miss: a map that spans half the depth range gets
// twice the layers where its relief is. (0, 1) for a map that spans it all.
fn relief_range(t0: f32) -> vec2f {
    let lo = clamp(max(t0, trace_params.depth_min), 0.0, 1.0);
    return vec2f(lo, clamp(trace_params.depth_max, lo, 1.0));
}

fn untraced(uv: vec2f) -> TraceResult {
    return TraceResult(uv, 0.0, 0u, false, 0u);
}
