// quadmax_pom: a bounded conservative skip, then a short POM search (the quadtree-displacement idea as a
// hybrid). The skip is quadmax's walk (common/quadmax.wgsl) cut after skip_steps steps: if it meets the surface
// within them its hit is quadmax's (exact on the packed leaves); otherwise it stops at a point t_s it proved free
// (everything before it is free too) and POM marches `layers` equal layers of [t_s, depth_max] from there, then
// interpolates linearly. APPROXIMATE: the march can step over a feature thinner than a layer, and the
// interpolation is a secant of the sampled surface; its error is measured (probe, benchmark), not bounded.
// Why: the skip removes the empty part of the ray at a bounded cost (no divergent long walk), so the layers
// that follow are denser than POM's over the whole depth range at the same count.
// Cost: at most 2 * skip_steps quadmax fetches, then layers + 1 depth fetches.
// #include "common/layer_march.wgsl"
// #include "common/quadmax.wgsl"

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let steps = clamp(trace_params.skip_steps, SKIP_STEPS_MIN, SKIP_STEPS_MAX);
    let skip = quadmax_walk(uv0, v, trace_params.top_offset, steps);
    if skip.found {
        return skip.result;  // (flagged capped at grazing views, like quadmax's own hits)
    }
    return pom_search(uv0, v, lod, skip.result.depth, clamp(trace_params.layers, LAYERS_MIN, LAYERS_MAX));
}
