// The max-pyramid walk of maxmip (Romanyuk & Dudnyk 2018, modified MIP pyramid), exact on the bilinear surface:
// maxmip runs it from the map's shallowest depth, distance and cone hand a grazing ray over to it (their steps
// crawl along the relief there, the pyramid skips whole nodes the ray passes above).
//
// The surface between four texel centres (a "cell", texel coordinates x = u * W - 0.5) is a bilinear patch, never
// higher than its highest corner. maps.py builds level 0 of the pyramid as that corner maximum per cell (wrap) and
// the coarser levels with maptools' maxmip kind (ceil-halving sizes; a parent covers at least the children 2i,
// 2i+1), so node i of level m bounds the cells [i * 2^m, (i + 1) * 2^m) of its row/column from above. The levels sit
// in one r32float atlas (level m at rows [row_m, row_m + h_m)), read with textureLoad: no sampler, no mip rules.
//
// Traversal: start at the top; at a node, compute where the ray leaves the node's cells; if it is still above the
// node's highest point there (t_exit < 1 - max), skip the node and look at the next one on the same level while it
// has the same parent (that parent was entered because the ray may reach its relief: testing it again would only
// descend again), else from one level up; otherwise descend. At level 0 the cell's exact quadratic is solved
// (cell_hit, common/cell.wgsl). The current cell is tracked as integers (stepped explicitly on exits), so rounding
// can never make the walk stall or go back. Addressing: the pyramid wraps (repeat), as the renderer's sampler does.
// #include "common/cell.wgsl"

// The handover of distance and cone: while the rest of the ray down to the floor spans more than HANDOVER_REACH cells
// (the walk pays its descent from the top, about log2 of the map's size in fetches, only on a long ray), a step of
// theirs is slow when it advances the ray (along its major axis) fewer than HANDOVER_CELLS cells, or so little that at
// its pace the rest of the ray would take more than HANDOVER_PACE steps (a ray far above a flat floor between distant
// peaks: long steps, but not long enough). After the registry's handover_steps slow steps the ray goes on with
// maxmip_walk.
const HANDOVER_REACH: f32 = 32.0;
const HANDOVER_CELLS: f32 = 2.0;
const HANDOVER_PACE: f32 = 32.0;

// 1 if the step from t to t_next (cells_per_t cells per unit t) is slow, else 0.
fn slow_step(t: f32, t_next: f32, cells_per_t: f32) -> u32 {
    let rest = (1.0 - t) * cells_per_t;
    let advance = (t_next - t) * cells_per_t;
    return select(0u, 1u, rest > HANDOVER_REACH && advance < max(HANDOVER_CELLS, rest / HANDOVER_PACE));
}

const MAXMIP_LEVELS: u32 = 16u;
// Float32 rounding of the stored maxima (height -> depth): skip only with this much room to spare.
const MAXMIP_MARGIN: f32 = 1e-6;

// The first hit after t_from (a point the caller has proven free) within `cap` steps; a capped walk returns its last
// free point, flagged. fetch_count goes on counting from the caller's value.
fn maxmip_walk(uv0: vec2f, v: vec3f, t_from: f32, cap: u32) -> TraceResult {
    let wh = vec2i(textureDimensions(depth_tex, 0));
    // Atlas row of each level; sizes ceil-halve down to 1x1 (maptools.cpu.level_sizes).
    var rows: array<i32, MAXMIP_LEVELS>;
    var lw = wh;
    var levels = 1u;
    while (lw.x > 1 || lw.y > 1) && levels < MAXMIP_LEVELS {
        rows[levels] = rows[levels - 1u] + lw.y;
        lw = (lw + 1) / 2;
        levels += 1u;
    }
    let top = levels - 1u;
    let span = parallax_span(v);
    let size = vec2f(wh);
    let start = uv0 * size - 0.5;
    let dir = -span * size;  // texel coordinates per unit t
    var t = t_from;
    var cell = vec2i(floor(start + t * dir));
    var level = top;
    for (var step = 0u; step < cap; step++) {
        let n = walk_node(cell, level, wh, start, dir);
        if level > 0u {
            fetch_count += 1u;
            let top_height = textureLoad(maxmip_tex, vec2i(n.index.x, rows[level] + n.index.y), 0).r;
            if n.t_exit >= 1.0 - top_height - MAXMIP_MARGIN {
                level -= 1u;  // the ray may reach this node's relief: look closer
                continue;
            }
        } else {
            let t_hit = cell_hit(cell, start, dir, t, n.t_exit);
            if t_hit >= 0.0 {
                return TraceResult(uv0 - span * t_hit, t_hit, fetch_count, is_grazing(v), 0u);
            }
        }
        // Nothing in this node: step into the next one along the ray, on this level within the same parent.
        t = max(t, n.t_exit);
        cell = next_cell(start, dir, t, n.exits, n.lo, n.hi);
        let same_parent = all((wrap_texel(cell, wh) >> vec2u(level + 1u)) == (n.index >> vec2u(1u)));
        level = select(min(level + 1u, top), level, same_parent && level < top);
    }
    return TraceResult(uv0 - span * t, t, fetch_count, true, 0u);
}
