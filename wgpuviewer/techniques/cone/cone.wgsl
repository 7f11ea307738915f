// Robust relaxed cone stepping, exact on the bilinear surface: maptools' relaxed cone map for the long
// skips, the exact cell solve of common/cell.wgsl wherever the cone step would not leave the current cell
// (the idea of Bán et al. 2024, "Robust Cone Step Mapping": never step less than to the cell's border),
// and an exact finish when a cone step ends inside the relief.
//
// The map and its contract are maptools' (docs/maps.md, "Relaxed cone map"): from any point p of texel q's
// footprint and any t < D(p), a ray segment inside the upward cone {(x, s): |x - p| <= c (D(p) - s)} has no
// solid -> free transition: it enters the relief at most once and never leaves it. cone_tex (rg32float, W x H,
// read with textureLoad = the nearest texel q, the lookup a filter = nearest map is built for) packs c (texels
// of u per unit of layer depth t) with d_q, the lowest depth in q's footprint (maps.footprint_min_depth: the
// minimum of the 3x3 texels the footprint's bilinear surface mixes). A cone whose apex is shallower than D(p)
// lies inside the true one, so any lower bound of D(p) may serve as the apex. A ray moves k = |V.xy / V.z| * S * W
// texels of u per unit t. Cell coordinates x = u * W - 0.5 (cells between texel centres, as cell.wgsl).
//
// The ray starts at the map's shallowest depth (depth_min): above it the ray meets nothing.
// A step from t (everything before t_free is proven free; t itself was reached by a cone step or a cell exit):
// 1. skip (after a cone step): read q's texel (1 fetch). If t < d_q the ray is free here; if the cone step
//    t_cone = t + (d_q - t) c / (k + c) also leaves the current cell, take it: 1 fetch per skip.
// 2. otherwise solve the cell exactly (1 gather) from t to its exit. A root after t is the first hit (a free
//    point reached by a cone step from a free one makes the whole step free). A root AT t after a cone step
//    means that step ended inside the relief: go to 4. No root: free up to the exit (t_free).
// 3. from the cell, cone step with the apex at the cell's lowest corner (<= D(p); all four corners lie in q's 3x3
//    neighbourhood, so it is never below d_q); the texel is read here only when even the widest stored cone could leave the cell (so
//    rays crawling along the surface pay 1 gather per cell). Go to t_cone if it lies past the cell's exit, else
//    to the exit (the next cell): every step leaves the cell, no Zeno crawl inside a cell.
// 4. a cone step [t_free, t] that ended solid holds ONE solid interval [t*, t]: halve it with exact bilinear
//    depths (1 gather each) until it spans at most one cell, then solve the cells it crosses exactly (at most 3,
//    plus the one its start may round into): the first root is t*.
// A grazing ray skims the relief: its cones stay narrow and it advances a cell or two per step. After handover_steps
// such slow steps (common/maxmip_walk.wgsl's slow_step) it finishes with the max-pyramid walk from t_free
// (common/maxmip_walk.wgsl, at most pyramid_steps steps), which skips whole nodes the ray passes above.
// Bounded: `iterations` steps of at most 2 fetches, then halvings_max halvings and finish_cells cells, or the
// pyramid walk's pyramid_steps (fixed values from the registry). A ray whose bracket the halvings cannot bring to one cell (float32 t runs out first) or whose
// finish finds no root to rounding ends at the bracket's free end, flagged.
// A capped ray returns its last free point t_free, flagged (short of the hit, never behind it).
// Grazing, horizontal and back-facing views are clamped by parallax_span and flagged (is_grazing).
// #include "common/cell.wgsl"
// #include "common/maxmip_walk.wgsl"

// (ratio c, footprint min depth d_q) of the texel q under the cell-coordinate point p: floor(u * W) = floor(x + 0.5).
fn cone_texel_at(p: vec2f, wh: vec2i) -> vec2f {
    fetch_count += 1u;
    return textureLoad(cone_tex, wrap_texel(vec2i(floor(p + 0.5)), wh), 0).rg;
}

// `layers` (the layers debug view): 1 where the bracket finish ran, else 0.
fn cone_result(uv0: vec2f, span: vec2f, t: f32, capped: bool, bracketed: bool) -> TraceResult {
    return TraceResult(uv0 - span * t, t, fetch_count, capped, select(0u, 1u, bracketed));
}

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let wh = vec2i(textureDimensions(depth_tex, 0));
    let span = parallax_span(v);
    let start = uv0 * vec2f(wh) - 0.5;
    let dir = -span * vec2f(wh);            // cell coordinates per unit t
    let k = length(span) * f32(wh.x);       // texels of u per unit t (the cone map's metric)
    let widest = trace_params.max_ratio;    // the map's largest stored ratio
    let cap = clamp(trace_params.iterations, ITERATIONS_MIN, ITERATIONS_MAX);
    let cells_per_t = max(abs(dir.x), abs(dir.y));
    var t = relief_range(0.0).x;  // depth_min (common/trace.wgsl)
    var t_free = t;     // the ray is free on [0, t_free]
    var cell = vec2i(floor(start + t * dir));
    // The last step went to a cell's exit (or, at the start, no cone could leave the first cell even with its apex
    // at the floor of the relief): the cell is solved first.
    var crawl = widest * (1.0 - t) <= (walk_node(cell, 0u, wh, start, dir).t_exit - t) * (k + widest);
    var bracketed = false;
    var slow = 0u;
    for (var i = 0u; i < cap; i++) {
        if slow >= trace_params.handover_steps {
            return maxmip_walk(uv0, v, t_free, trace_params.pyramid_steps);
        }
        let n = walk_node(cell, 0u, wh, start, dir);
        if n.t_exit <= t && t < 1.0 {
            // A cone step's end rounded into a cell the ray has already left: move on (no fetch, no stall).
            cell = next_cell(start, dir, t, n.exits, n.lo, n.hi);
            continue;
        }
        var texel = vec2f(-1.0);  // (c, d_q) once read
        if !crawl {
            texel = cone_texel_at(start + t * dir, wh);
            if t < texel.y {
                let t_cone = t + (texel.y - t) * texel.x / (k + texel.x);
                if t_cone > n.t_exit && t_cone > t {
                    slow += slow_step(t, t_cone, cells_per_t);
                    t_free = t;
                    t = t_cone;
                    cell = vec2i(floor(start + t * dir));
                    continue;
                }
            }
        }
        let corners = cell_corners(cell);
        let hit = cell_root(corners, cell, start, dir, t, n.t_exit);
        if hit >= 0.0 {
            if hit > t || t <= t_free {
                return cone_result(uv0, span, hit, is_grazing(v), false);
            }
            bracketed = true;  // the cone step [t_free, t] ended inside the relief
            break;
        }
        t_free = n.t_exit;
        // The cell's lowest corner bounds D(p) from below (and is at least d_q: the corners lie in q's 3x3).
        let apex = min(min(corners.x, corners.y), min(corners.z, corners.w));
        if texel.x < 0.0 && (apex - t) * widest > (n.t_exit - t) * (k + widest) {
            texel = cone_texel_at(start + t * dir, wh);
        }
        var t_next = n.t_exit;
        if texel.x >= 0.0 && apex > t {
            t_next = max(t_next, t + (apex - t) * texel.x / (k + texel.x));
        }
        crawl = t_next <= n.t_exit;
        slow += slow_step(t, t_next, cells_per_t);
        if crawl {
            t = n.t_exit;
            cell = next_cell(start, dir, t, n.exits, n.lo, n.hi);
        } else {
            t = t_next;
            cell = vec2i(floor(start + t * dir));
        }
    }
    if !bracketed {
        return cone_result(uv0, span, t_free, true, false);
    }
    // [lo, hi]: free at lo, solid at hi, one solid interval inside.
    var lo = t_free;
    var hi = t;
    for (var h = 0u; h < trace_params.halvings_max && (hi - lo) * cells_per_t > 1.0; h++) {
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
    for (var s = 0u; s < trace_params.finish_cells; s++) {
        let n = walk_node(cell, 0u, wh, start, dir);
        if n.t_exit > t || t >= 1.0 {  // else lo rounded into a cell the ray has already left: no solve there
            let hit = cell_root(cell_corners(cell), cell, start, dir, t, min(n.t_exit, hi));
            if hit >= 0.0 {
                return cone_result(uv0, span, hit, is_grazing(v), true);
            }
            if n.t_exit >= hi {
                break;
            }
            t = n.t_exit;
        }
        cell = next_cell(start, dir, t, n.exits, n.lo, n.hi);
    }
    // Rounding (or the halving cap) left no root found in [lo, hi]: stop at the free end, flagged.
    return cone_result(uv0, span, lo, true, true);
}
