// Self-shadowing of a traced point by the relief, towards a directional light L (tangent space, towards the
// light). The definition is wgpuviewer/relief/reference.py's `shadow` (its float64 twin); SHADOW_TOLERANCE_TEXELS,
// SOFT_SHADOW_SAMPLES and SOFT_SHADOW_PENUMBRA are generated from it (relief/shaders.py).
//
// Hard: the light ray enters the relief's top above the point (uv + t * span) and descends towards it; the
// technique's own `trace` finds its first hit, so every technique's shadow has that technique's accuracy and cost.
// The point is lit iff that hit lies within SHADOW_TOLERANCE_TEXELS of travel before the point itself.
// Soft: the largest elevation (tangent) of the relief above the light ray seen from the surface point at the hit's
// uv, over SOFT_SHADOW_SAMPLES depth samples from the tolerance up to the top, mapped linearly onto [0, 1] by the
// penumbra.
// Lights at or below the horizon (L.z <= 0) shadow; grazing lights are clamped by parallax_span (finite, flagged).
// #include "common/trace.wgsl"

struct ShadowResult {
    visibility: f32,  // 1 lit, 0 shadowed; soft: in between
    fetches: u32,     // depth fetches the shadow ray spent
    capped: bool,     // a cap or clamp decided it (grazing light, a capped trace)
}

// The tolerance as layer depth on a light ray of this span: one SHADOW_TOLERANCE_TEXELS of travel.
fn shadow_tolerance(span: vec2f) -> f32 {
    let texels = length(span * vec2f(f32(trace_params.depth_width), f32(trace_params.depth_height)));
    return SHADOW_TOLERANCE_TEXELS / max(texels, 1e-30);
}

fn shadow_hard(uv: vec2f, t: f32, l: vec3f, lod: f32) -> ShadowResult {
    if l.z <= 0.0 {
        return ShadowResult(0.0, 0u, false);
    }
    let span = parallax_span(l);
    let tolerance = shadow_tolerance(span);
    if t <= tolerance {
        return ShadowResult(1.0, 0u, is_grazing(l));  // no room for an occluder (a vertical light among them)
    }
    let r = trace(uv + span * t, l, lod);
    return ShadowResult(select(0.0, 1.0, r.depth >= t - tolerance), r.fetches, r.capped || is_grazing(l));
}

// From the surface point at uv (its depth sampled, not the view search's t: a search that stops a little below the
// surface, as fixed steps do, would see the relief rise right above its hit everywhere).
fn shadow_soft(uv: vec2f, l: vec3f) -> ShadowResult {
    if l.z <= 0.0 {
        return ShadowResult(0.0, 0u, false);
    }
    let span = parallax_span(l);
    let tolerance = shadow_tolerance(span);
    let t = textureSampleLevel(depth_tex, material_sampler, uv, 0.0).r;
    if t <= tolerance {
        return ShadowResult(1.0, 1u, is_grazing(l));
    }
    let reach = t - tolerance;
    let tan_light = length(l.xy) / max(l.z, MIN_VIEW_Z);
    var worst = 0.0;
    for (var i = 0u; i < SOFT_SHADOW_SAMPLES; i++) {
        let t_s = reach * (1.0 - f32(i) / f32(SOFT_SHADOW_SAMPLES - 1u));
        let d = textureSampleLevel(depth_tex, material_sampler, uv + span * (t - t_s), 0.0).r;
        worst = max(worst, (t_s - d) / ((t - t_s) * tan_light));
    }
    return ShadowResult(clamp(1.0 - worst / SOFT_SHADOW_PENUMBRA, 0.0, 1.0), SOFT_SHADOW_SAMPLES + 1u, is_grazing(l));
}
