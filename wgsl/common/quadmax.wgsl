// Max-quadtree tracing with packed leaves (the quadmax technique; auto uses it for steep views), never behind
// the first hit of the bilinear surface.
//
// The map (wgpuviewer/relief/maps.py, quadmax_atlas; rgba32uint, read with textureLoad) is a quadtree over the
// bilinear cells (texel coordinates x = u * W - 0.5), node level m covering the cells [i 2^m, (i + 1) 2^m):
// - a level-1 node (2x2 cells) is a LEAF: one texel packs the 9 texel depths of its block as 14-bit
//   q = floor(D * 16383) (rounded down: the leaf's surface is never below the true one, by at most 6.1e-5);
// - a node of level m >= 2 holds the maxima of its four children (level m - 1; float32 bits; maptools' max
//   pyramid over the cells' corner maxima): one fetch tells which children the ray passes above.
// The walk is maxmip's (integer cell state, box exits; wgsl/techniques/maxmip.wgsl) with three changes:
// it starts at level top = floor(log2(ray reach in texels)) + top_offset (at least 1) instead of the root
// (coarse nodes of a rough map all reach the top of the relief: visiting them buys nothing); the node
// test reads the parent's texel, kept per level, so going to a sibling or back up costs no fetch; and a
// leaf is solved with one fetch: the exact quadratic of each of its (at most 3) cells the ray crosses
// (cell_root), on the quantised depths. A hit of the leaves' surface is never behind the true first hit.
// Fetches: one per quad texel read + one per leaf; at most 2 per step.
// #include "common/cell.wgsl"
// #include "common/wrap.wgsl"

const QUAD_LEVELS: u32 = 16u;
// Float32 rounding of the stored maxima (height -> depth): skip only with this much room to spare.
const QUAD_MARGIN: f32 = 1e-6;
const LEAF_SCALE: f32 = 16383.0;

// Depth k (0..8; k = 3 * row + column of the leaf's 3x3 texels) of a packed leaf: bits [14 k, 14 k + 14)
// of the four words (little-endian), maps.pack_leaves.
fn leaf_depth(w: vec4u, k: u32) -> f32 {
    let bit = 14u * k;
    let word = bit / 32u;
    let shift = bit % 32u;
    var q = w[word] >> shift;
    if shift > 18u {
        q |= w[word + 1u] << (32u - shift);
    }
    return f32(q & 0x3fffu) / LEAF_SCALE;
}

// First hit inside the leaf [lo, hi) (packed depths w) of the ray start + t * dir, from cell at t0 until
// it leaves the leaf at t_exit; -1 if none. No fetch: the leaf is already read.
fn leaf_hit(w: vec4u, lo: vec2i, hi: vec2i, cell0: vec2i, start: vec2f, dir: vec2f, t0: f32, t_exit: f32) -> f32 {
    var cell = cell0;
    var t = t0;
    for (var k = 0u; k < 4u; k++) {  // a segment crosses at most 3 of the 4 cells
        let l = cell - lo;
        let i = u32(l.x + 3 * l.y);
        let c = vec4f(leaf_depth(w, i), leaf_depth(w, i + 1u), leaf_depth(w, i + 3u), leaf_depth(w, i + 4u));
        let exits = box_exit(start, dir, vec2f(cell), vec2f(cell) + 1.0);
        let t1 = min(min(exits.x, exits.y), t_exit);
        let t_hit = cell_root(c, cell, start, dir, t, t1);
        if t_hit >= 0.0 {
            return t_hit;
        }
        if t1 >= t_exit {
            break;
        }
        t = t1;
        cell += vec2i(select(0, select(-1, 1, dir.x > 0.0), exits.x <= t1),
                      select(0, select(-1, 1, dir.y > 0.0), exits.y <= t1));
        if any(cell < lo) || any(cell >= hi) {
            break;
        }
    }
    return -1.0;
}

fn quadmax_search(uv0: vec2f, v: vec3f, top_offset: f32, max_steps: u32) -> TraceResult {
    let wh = vec2i(textureDimensions(depth_tex, 0));
    // Atlas row of each level >= 1; sizes ceil-halve from ceil(wh / 2) at level 1 down to 1x1.
    var rows: array<i32, QUAD_LEVELS>;
    var lw = (wh + 1) / 2;
    var levels = 2u;
    while (lw.x > 1 || lw.y > 1) && levels < QUAD_LEVELS {
        rows[levels] = rows[levels - 1u] + lw.y;
        lw = (lw + 1) / 2;
        levels += 1u;
    }
    let span = parallax_span(v);
    let size = vec2f(wh);
    let start = uv0 * size - 0.5;
    let dir = -span * size;  // texel coordinates per unit t
    let top = u32(clamp(floor(log2(max(length(dir), 1.0))) + top_offset, 1.0, f32(levels - 1u)));
    // Per level: the quad texel read last (the node whose children's maxima it holds).
    var quad_node: array<vec2i, QUAD_LEVELS>;
    var quad_max: array<vec4f, QUAD_LEVELS>;
    for (var k = 0u; k < QUAD_LEVELS; k++) {
        quad_node[k] = vec2i(-1);
    }
    var cell = vec2i(floor(start));
    var t = 0.0;
    var level = top;
    for (var step = 0u; step < max_steps; step++) {
        let wrapped = wrap_texel(cell, wh);
        let node = wrapped >> vec2u(level);
        let first = node << vec2u(level);
        let lo = cell - wrapped + first;                           // the node's cells, unwrapped
        let hi = lo + min(vec2i(1 << level), wh - first);
        let exits = box_exit(start, dir, vec2f(lo), vec2f(hi));
        let t_exit = min(min(exits.x, exits.y), 1.0);
        // May the ray reach this node's relief? Its maximum is in the parent's texel (none for the root;
        // leaves-only walks, top = 1, read the leaves directly).
        var reach = true;
        let up = level + 1u;
        if up < levels && top > 1u {
            let parent = node >> vec2u(1u);
            if any(quad_node[up] != parent) {
                fetch_count += 1u;
                quad_node[up] = parent;
                quad_max[up] = bitcast<vec4f>(textureLoad(quadmax_tex, vec2i(parent.x, rows[up] + parent.y), 0));
            }
            let child = node & vec2i(1);
            reach = t_exit >= 1.0 - quad_max[up][child.x + 2 * child.y] - QUAD_MARGIN;
        }
        if reach {
            if level > 1u {
                level -= 1u;  // look closer
                continue;
            }
            fetch_count += 1u;
            let leaf = textureLoad(quadmax_tex, node, 0);
            let t_hit = leaf_hit(leaf, lo, hi, cell, start, dir, t, t_exit);
            if t_hit >= 0.0 {
                return TraceResult(uv0 - span * t_hit, t_hit, fetch_count, is_grazing(v), 0u);
            }
        }
        // Nothing in this node: step into the next one along the ray and look from one level up.
        t = max(t, t_exit);
        let p = floor(start + t * dir);
        cell = vec2i(
            select(clamp(i32(p.x), lo.x, hi.x - 1), select(lo.x - 1, hi.x, dir.x > 0.0), exits.x <= t_exit),
            select(clamp(i32(p.y), lo.y, hi.y - 1), select(lo.y - 1, hi.y, dir.y > 0.0), exits.y <= t_exit),
        );
        level = min(level + 1u, top);
    }
    return TraceResult(uv0 - span * t, t, fetch_count, true, 0u);
}
