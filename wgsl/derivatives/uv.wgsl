// Derivative source `uv`: the screen-space derivatives of the unperturbed surface uv, as before the ray search
// (what the renderer always used). Called in uniform control flow, before any discard.
// #include "common/footprint.wgsl"

fn texture_derivatives(uv0: vec2f, v: vec3f, hit: TraceResult) -> Derivatives {
    return Derivatives(dpdx(uv0), dpdy(uv0), 1.0, 0u);
}
