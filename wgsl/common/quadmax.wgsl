// Max-quadtree tracing with packed leaves (the quadmax technique; auto uses it for steep views), never behind
// the first hit of the bilinear surface.
//
// The map (wgpuviewer/relief/maps.py, quadmax_atlas; rgba32uint, read with textureLoad) is a quadtree over the
// bilinear cells (texel coordinates x = u * W - 0.5), node level m covering the cells [i 2^m, (i + 1) 2^m):
// - a level-1 node (2x2 cells) is a LEAF: one texel packs the 9 texel depths of its block as 14-bit
//   q = floor(D * 16383) (rounded down: the leaf's surface is never below the true one, by at most 6.1e-5);
// - a node of level m >= 2 holds the maxima of its four children (level m - 1; float32 bits; maptools' max
//   pyramid over the cells' corner maxima): one fetch tells which children the ray passes above.
// The walk is maxmip's (integer cell state, box exits; wgsl/common/maxmip_walk.wgsl) with three changes:
// it starts at level top = floor(log2(ray reach in texels)) + top_offset (at least 1) instead of the root
// (coarse nodes of a rough map all reach the top of the relief: visiting them buys nothing); the node
// test reads the parent's texel, kept (one for even, one for odd levels), so going to a sibling or back up
// costs no fetch; and a leaf is solved with one fetch: the exact quadratic of each of its (at most 3) cells
// the ray crosses (cell_root), on the quantised depths. A hit of the leaves' surface is never behind the true first hit.
// Fetches: one per quad texel read + one per leaf; at most 2 per step.
// #include "common/cell.wgsl"

// Float32 rounding of the stored maxima (height -> depth): skip only with this much room to spare.
const QUAD_MARGIN: f32 = 1e-6;
const LEAF_SCALE: f32 = 16383.0;

// Depth k (0..8; k = 3 * row + column of the leaf's 3x3 texels) of a packed leaf: bits [14 k, 14 k + 14)
// of the four words (little-endian), maps.pack_leaves (its 2^-8 / 16383 = 2.4e-7 margin covers the rounding of
// the multiply below: within 1.2e-7 of q / 16383, for one multiply instead of 9 divisions per leaf).
fn leaf_depth(w: vec4u, k: u32) -> f32 {
    let bit = 14u * k;
    let word = bit / 32u;
    let shift = bit % 32u;
    var q = w[word] >> shift;
    if shift > 18u {
        q |= w[word + 1u] << (32u - shift);
    }
    return f32(q & 0x3fffu) * (1.0 / LEAF_SCALE);
}

// The value of the 2x2 quadrant (x: column, y: row of the cell in its leaf) among a, b (top row), c, d.
fn quadrant(l: vec2i, a: f32, b: f32, c: f32, d: f32) -> f32 {
    return select(select(a, b, l.x == 1), select(c, d, l.x == 1), l.y == 1);
}

// First hit inside the leaf [lo, hi) (packed depths w) of the ray start + t * dir, from cell at t0 until
// it leaves the leaf at t_exit; -1 if none. No fetch: the leaf is already read.
fn leaf_hit(w: vec4u, lo: vec2i, hi: vec2i, cell0: vec2i, start: vec2f, dir: vec2f, t0: f32, t_exit: f32) -> f32 {
    let d0 = leaf_depth(w, 0u);
    let d1 = leaf_depth(w, 1u);
    let d2 = leaf_depth(w, 2u);
    let d3 = leaf_depth(w, 3u);
    let d4 = leaf_depth(w, 4u);
    let d5 = leaf_depth(w, 5u);
    let d6 = leaf_depth(w, 6u);
    let d7 = leaf_depth(w, 7u);
    let d8 = leaf_depth(w, 8u);
    var cell = cell0;
    var t = t0;
    for (var k = 0u; k < 4u; k++) {  // a segment crosses at most 3 of the 4 cells
        let l = cell - lo;
        let c = vec4f(quadrant(l, d0, d1, d3, d4), quadrant(l, d1, d2, d4, d5),
                      quadrant(l, d3, d4, d6, d7), quadrant(l, d4, d5, d7, d8));
        let exits = box_exit(start, dir, vec2f(cell), vec2f(cell) + 1.0);
        let t1 = min(min(exits.x, exits.y), t_exit);
        // The patch is nowhere above its shallowest corner: a ray still above that at t1 misses the cell.
        if t1 >= min(min(c.x, c.y), min(c.z, c.w)) || t1 >= 1.0 {
            let t_hit = cell_root(c, cell, start, dir, t, t1);
            if t_hit >= 0.0 {
                return t_hit;
            }
        }
        if t1 >= t_exit {
            break;
        }
        t = max(t, t1);  // a cell the ray only grazes by rounding exits before t: never step back
        cell += vec2i(select(0, select(-1, 1, dir.x > 0.0), exits.x <= t1),
                      select(0, select(-1, 1, dir.y > 0.0), exits.y <= t1));
        if any(cell < lo) || any(cell >= hi) {
            break;
        }
    }
    return -1.0;
}

// Atlas row of node level m >= 1: level 1 (the leaves) first, then the levels of ceil(rows / 2^k) rows:
// sum over k in [1, m) of ceil(rows / 2^k) = floor((rows - 1) / 2^k) + 1, in closed form with
// sum over k in [1, K] of floor(n / 2^k) = n - popcount(n) - q + popcount(q), q = n >> K.
fn quad_row(rows: i32, m: u32) -> i32 {
    let n = u32(rows - 1);
    let q = n >> (m - 1u);
    return i32(n - countOneBits(n) - q + countOneBits(q) + m - 1u);
}

// The walk's outcome: its result, and whether it met the surface (false: the step cap ended it at result.depth,
// a point proven free; quadmax_pom continues from there).
struct QuadmaxWalk {
    result: TraceResult,
    found: bool,
}

fn quadmax_search(uv0: vec2f, v: vec3f, top_offset: i32, max_steps: u32) -> TraceResult {
    return quadmax_walk(uv0, v, top_offset, max_steps).result;
}

fn quadmax_walk(uv0: vec2f, v: vec3f, top_offset: i32, max_steps: u32) -> QuadmaxWalk {
    let wh = vec2i(textureDimensions(depth_tex, 0));
    // The root: the first level (>= 1) of one node (sizes ceil-halve: level m has ceil(W / 2^m) columns).
    let root = max(1u, 32u - countLeadingZeros(u32(max(wh.x, wh.y) - 1)));
    let span = parallax_span(v);
    let size = vec2f(wh);
    let start = uv0 * size - 0.5;
    let dir = -span * size;  // texel coordinates per unit t
    let top = u32(clamp(floor(log2(max(length(dir), 1.0))) + f32(top_offset), 1.0, f32(root)));
    // The quad texels read last, one for the even and one for the odd levels (the walk tests a node with its
    // parent's texel and moves between neighbouring levels: two slots keep nearly every reuse).
    // (tagged with the level: nodes of two levels may have the same coordinates).
    var even_node = vec3i(-1);
    var even_max = vec4f(0.0);
    var odd_node = vec3i(-1);
    var odd_max = vec4f(0.0);
    // Above the map's shallowest depth the ray meets nothing: the walk starts there (relief_range, common/trace.wgsl).
    var t = relief_range(0.0).x;
    var cell = vec2i(floor(start + t * dir));
    var level = top;
    var step = 0u;  // steps: a descent, a node passed above, a leaf solved; at most max_steps in all
    // Two loops, as Aila & Laine's "while-while" traversal: the inner one walks the nodes until one is a leaf the ray
    // may reach, then that leaf is solved. The lanes of a SIMD group then run the (long) leaf solve together instead
    // of each step paying for it whenever one lane has a leaf (llvmpipe: -13 to -25 % time where the walk has inner
    // nodes, docs/techniques.md). Same steps, fetches and hits as one loop doing either per step.
    for (var leaves = 0u; leaves < max_steps; leaves++) {
        var n: WalkNode;
        while step < max_steps {
            n = walk_node(cell, level, wh, start, dir);
            // May the ray reach this node's relief? Its maximum is in the parent's texel (none for the root;
            // leaves-only walks, top = 1, read the leaves directly).
            var reach = true;
            let up = level + 1u;
            if up <= root && top > 1u {
                let parent = n.index >> vec2u(1u);
                let tag = vec3i(parent, i32(up));
                let odd = (up & 1u) == 1u;
                if any(select(even_node, odd_node, odd) != tag) {
                    fetch_count += 1u;
                    let quad = bitcast<vec4f>(textureLoad(quadmax_tex, vec2i(parent.x, quad_row(wh.y, up) + parent.y), 0));
                    if odd {
                        odd_node = tag;
                        odd_max = quad;
                    } else {
                        even_node = tag;
                        even_max = quad;
                    }
                }
                let maxima = select(even_max, odd_max, odd);
                let child = n.index & vec2i(1);
                let top_height = select(select(maxima.x, maxima.y, child.x == 1), select(maxima.z, maxima.w, child.x == 1),
                                        child.y == 1);
                reach = n.t_exit >= 1.0 - top_height - QUAD_MARGIN;
            }
            if reach {
                if level == 1u {
                    break;  // a leaf to solve
                }
                level -= 1u;  // look closer
                step++;
                continue;
            }
            let next = step_past(n, cell, level, top, t, start, dir, wh);
            cell = next.cell;
            level = next.level;
            t = next.t;
            step++;
        }
        if step >= max_steps {
            break;
        }
        fetch_count += 1u;
        let leaf = textureLoad(quadmax_tex, n.index, 0);
        let t_hit = leaf_hit(leaf, n.lo, n.hi, cell, start, dir, t, n.t_exit);
        if t_hit >= 0.0 {
            return QuadmaxWalk(TraceResult(uv0 - span * t_hit, t_hit, fetch_count, is_grazing(v), 0u), true);
        }
        let next = step_past(n, cell, 1u, top, t, start, dir, wh);
        cell = next.cell;
        level = next.level;
        t = next.t;
        step++;
    }
    return QuadmaxWalk(TraceResult(uv0 - span * t, t, fetch_count, true, 0u), false);
}

// Where the walk goes on after node n (at `level`) held nothing for the ray: into the next node along the ray,
// looked at from one level up only when that one is in another parent (this parent was entered because the ray may
// reach its relief, and still may).
struct WalkStep {
    cell: vec2i,
    level: u32,
    t: f32,
}

fn step_past(n: WalkNode, cell: vec2i, level: u32, top: u32, t: f32, start: vec2f, dir: vec2f, wh: vec2i) -> WalkStep {
    let t_next = max(t, n.t_exit);
    let next = next_cell(start, dir, t_next, n.exits, n.lo, n.hi);
    let up = level + 1u;
    let same_parent = all((wrap_texel(next, wh) >> vec2u(up)) == (n.index >> vec2u(1u)));
    return WalkStep(next, select(min(up, top), level, same_parent && level < top), t_next);
}
