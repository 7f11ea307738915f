// Robust relaxed cone stepping, exact on the bilinear surface: maptools' relaxed cone map for the long
// skips, the exact cell solve of common/cell.wgsl wherever the cone step would not leave the current cell
// (the idea of Bán et al. 2024, "Robust Cone Step Mapping": never step less than to the cell's border),
// and an exact finish when a cone step ends inside the relief.
//
// The map and its contract are maptools' (docs/maps.md, "Relaxed cone map"): cone_tex (r32float, W x H,
// read with textureLoad = the nearest texel q, the lookup a filter = nearest map is built for) stores c in
// texels of u per unit of layer depth t, such that from any point p of q's footprint and any t < D(p), a ray
// segment inside the upward cone {(x, s): |x - p| <= c (D(p) - s)} has no solid -> free transition: it
// enters the relief at most once and never leaves it. A ray moves k = |V.xy / V.z| * S * W texels of u per
// unit t. Cell coordinates x = u * W - 0.5 (cells between texel centres, as cell.wgsl).
//
// Per step, at a point (p, t) that is free or was reached by a cone step:
// 1. gather the corners of p's cell (1 fetch) and solve the cell exactly from t to where the ray leaves it.
//    A root after t is the first hit (everything before t is free, see 3), returned exactly. A root AT t
//    after a cone step means that step ended inside the relief: go to 4.
// 2. the ray is free up to the cell's exit t_exit (t_free = t_exit).
// 3. relaxed cone step: the apex depth D(p) is at least the cell's lowest corner d_lo, and the cone of a
//    shallower apex lies inside the cone of the true one, so t_cone = t + (d_lo - t) c / (k + c) (cone fetch:
//    1 fetch, skipped when even the widest stored cone could not pass t_exit) keeps the guarantee. Go to
//    t_cone if it lies past t_exit, else to t_exit (next cell). No Zeno crawl: every step leaves the cell.
//    A cone step that ends free was free throughout (free -> solid -> free is excluded), so the next
//    step's start is again preceded by free ray only.
// 4. a cone step [t_free, t] ended solid: the relief there is ONE interval [t*, t]. Halve the bracket
//    with exact bilinear depths (1 gather each) until it spans at most one cell, then solve the (at most
//    3) cells it crosses exactly: the first root is t*.
// Bounded: `iterations` steps of at most 2 fetches, then halvings_max halvings and finish_cells cells
// (fixed values from the registry: enough halvings for any bracket, and a one-cell bracket crosses <= 3 cells).
// A capped ray returns its last free point t_free, flagged (short of the hit, never behind it).
// Grazing, horizontal and back-facing views are clamped by parallax_span and flagged (is_grazing).
// #include "common/cell.wgsl"

fn cone_ratio_at(p: vec2f, wh: vec2i) -> f32 {
    fetch_count += 1u;
    // Texel q of the cell-coordinate point p: floor(u * W) = floor(x + 0.5).
    return textureLoad(cone_tex, wrap_texel(vec2i(floor(p + 0.5)), wh), 0).r;
}

fn cone_hit(uv0: vec2f, span: vec2f, t: f32, v: vec3f) -> TraceResult {
    return TraceResult(uv0 - span * t, t, fetch_count, is_grazing(v), 0u);
}

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let wh = vec2i(textureDimensions(depth_tex, 0));
    let span = parallax_span(v);
    let start = uv0 * vec2f(wh) - 0.5;
    let dir = -span * vec2f(wh);            // cell coordinates per unit t
    let k = length(span) * f32(wh.x);       // texels of u per unit t (the cone map's metric)
    let widest = trace_params.max_ratio;    // the map's largest stored ratio
    let cap = u32(clamp(trace_params.iterations, 1.0, ITERATIONS_MAX));
    var t = 0.0;
    var t_free = 0.0;  // the ray is free on [0, t_free]
    var cell = vec2i(floor(start));
    var bracketed = false;
    for (var i = 0u; i < cap; i++) {
        let n = walk_node(cell, 0u, wh, start, dir);
        let c = cell_corners(cell);
        let hit = cell_root(c, cell, start, dir, t, n.t_exit);
        if hit >= 0.0 {
            if hit > t || t <= t_free {
                return cone_hit(uv0, span, hit, v);
            }
            bracketed = true;  // the cone step [t_free, t] ended inside the relief
            break;
        }
        t_free = n.t_exit;
        let gap = min(min(c.x, c.y), min(c.z, c.w)) - t;
        var t_next = n.t_exit;
        if gap * widest > (n.t_exit - t) * (k + widest) {
            let ratio = cone_ratio_at(start + t * dir, wh);
            t_next = max(t_next, t + gap * ratio / (k + ratio));
        }
        if t_next > n.t_exit {
            t = t_next;
            cell = vec2i(floor(start + t * dir));
        } else {
            t = n.t_exit;
            cell = next_cell(start, dir, t, n.exits, n.lo, n.hi);
        }
    }
    if !bracketed {
        return TraceResult(uv0 - span * t_free, t_free, fetch_count, true, 0u);
    }
    // [lo, hi]: free at lo, solid at hi, one solid interval inside.
    var lo = t_free;
    var hi = t;
    let cells_per_t = max(abs(dir.x), abs(dir.y));
    for (var h = 0u; h < u32(trace_params.halvings_max) && (hi - lo) * cells_per_t > 1.0; h++) {
        let mid = 0.5 * (lo + hi);
        let p = start + mid * dir;
        let mc = vec2i(floor(p));
        if mid >= cell_depth(cell_corners(mc), clamp(p - vec2f(mc), vec2f(0.0), vec2f(1.0))) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    t = lo;
    cell = vec2i(floor(start + lo * dir));
    for (var s = 0u; s < u32(trace_params.finish_cells); s++) {
        let n = walk_node(cell, 0u, wh, start, dir);
        let hit = cell_root(cell_corners(cell), cell, start, dir, t, min(n.t_exit, hi));
        if hit >= 0.0 {
            return cone_hit(uv0, span, hit, v);
        }
        if n.t_exit >= hi {
            break;
        }
        t = n.t_exit;
        cell = next_cell(start, dir, t, n.exits, n.lo, n.hi);
    }
    // Rounding (or the halving cap) left no root found in [lo, hi]: stop at the free end, flagged.
    return TraceResult(uv0 - span * lo, lo, fetch_count, true, 0u);
}
