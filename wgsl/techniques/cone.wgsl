// Relaxed cone stepping (Policarpo & Oliveira 2007) on maptools' conservative cone map, then a
// binary refinement of the bracket. The map and its contract are maptools' (docs/maps.md, "Relaxed
// cone map"): cone_tex (r32float, W x H, read with textureLoad = NEAREST texel, the lookup the map was
// built for: filter = nearest) stores c in texels of u per unit of layer depth t. A ray moves
// k = |V.xy / V.z| * S * W texels of u per unit t. From a free point at depth t over p, the step
// dt = (D(p) - t) * c / (k + c) stays inside the upward cone of p, where the map guarantees no
// solid -> free transition: a step that ends free was free throughout, so the cone phase never passes
// the first hit (t_prev <= t*), and within the final step the solid part is one interval [t*, t].
//
// Ends of the cone phase (at most `iterations` steps, each 1 depth + 1 cone fetch):
// - bracket (t >= D): binary_steps halvings of [t_prev, t] keep a free lower and a solid upper end;
//   the FREE end is returned, so the result never lies behind the first hit (error <= bracket / 2^n);
// - gap stop (D - t <= gap_stop): the ray is that close above the surface; returned as is (the cones
//   near the surface are narrow, so rays converge onto it geometrically rather than bracket it);
// - step cap: the last checked (free) point, flagged capped (short of the hit, never behind it).
// Grazing, horizontal and back-facing views are clamped by parallax_span and flagged (is_grazing).
// #include "common/binary.wgsl"
// #include "common/wrap.wgsl"

fn cone_at(uv: vec2f, size: vec2i) -> f32 {
    fetch_count += 1u;
    let texel = vec2i(floor(uv * vec2f(size)));
    return textureLoad(cone_tex, wrap_texel(texel, size), 0).r;
}

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let size = vec2i(textureDimensions(cone_tex, 0));
    let span = parallax_span(v);
    let k = length(span) * f32(size.x);  // texels of u per unit t
    let cap = u32(clamp(trace_params.iterations, 1.0, ITERATIONS_MAX));
    let gap = max(trace_params.gap_stop, 0.0);
    var t = 0.0;
    var t_prev = 0.0;
    var ended = 0u;  // 0: step cap, 1: bracket, 2: gap stop
    for (var i = 0u; i < cap; i++) {
        let uv = uv0 - span * t;
        let d = depth_at(uv, lod);
        if t >= d {
            ended = 1u;
            break;
        }
        if d - t <= gap {
            ended = 2u;
            break;
        }
        let c = cone_at(uv, size);
        var frac = 1.0;
        if k > 0.0 {
            frac = c / (k + c);
        }
        t_prev = t;
        t = min(t + (d - t) * frac, 1.0);
    }
    let grazing = is_grazing(v);
    if ended == 0u {
        // The last step's end was never checked: stop at the last point known to be free.
        return TraceResult(uv0 - span * t_prev, t_prev, fetch_count, true, 0u);
    }
    if ended == 2u {
        return TraceResult(uv0 - span * t, t, fetch_count, grazing, 0u);
    }
    if k == 0.0 {
        // Head-on: the step landed exactly on the surface below uv0 (t = D(uv0)); no search needed.
        return TraceResult(uv0, t, fetch_count, grazing, 0u);
    }
    // [t_prev, t]: free at t_prev, solid at t.
    let nb = u32(clamp(trace_params.binary_steps, 0.0, BINARY_STEPS_MAX));
    let lo = binary_refine(uv0, span, t_prev, t, nb, lod).x;
    return TraceResult(uv0 - span * lo, lo, fetch_count, grazing, 0u);
}
