// Distance-map parallax (Donnelly), shared by `distance` and `distance_refined`: the loop is the same,
// only the volume bound at distance_tex differs (plain or visibility-refined map, maptools).
//
// Metric (docs/maps.md): X = u * W, Y = v * W, Z = t * S * W, one unit = one texel along u. The volume
// (W, H, slices) stores per voxel a radius that a NEAREST lookup anywhere in the voxel may step
// without reaching the relief (for the refined map: along any ray of the admissible cone that got
// there unoccluded). The ray moves per unit t by |(span, S)| * W in that metric, so a radius r is a
// step of r / that in t. Where that step would not even leave the current bilinear cell (close to the
// surface radii shrink towards 0 and sphere tracing crawls), the cell is solved exactly (cell_hit,
// common/cell.wgsl) and left at its exit if it holds no hit: the tracer never passes
// through a surface and its hit is exact to float32. Rays steeper than the map's cone (cone_cos, fixed
// by the technique) take only exact cell steps. Bounded by `iterations` (capped rays are flagged and
// stop short of the surface, never behind it).
// #include "common/cell.wgsl"
// #include "common/wrap.wgsl"

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let vol = vec3i(textureDimensions(distance_tex, 0));
    let size = vec2f(vol.xy);
    let span = parallax_span(v);
    let start = uv0 * size - 0.5;
    let dir = -span * size;
    let per_t = size.x * length(vec3f(span, trace_params.height_scale));
    let admissible = v.z >= trace_params.cone_cos * length(v);
    let cap = u32(clamp(trace_params.iterations, 1.0, ITERATIONS_MAX));
    var t = 0.0;
    for (var step = 0u; step < cap; step++) {
        let texel = vec2i(floor((uv0 - span * t) * size));
        let k = clamp(i32(floor(t * f32(vol.z))), 0, vol.z - 1);
        fetch_count += 1u;
        let radius = textureLoad(distance_tex, vec3i(wrap_texel(texel, vol.xy), k), 0).r;
        // The cell the ray is in (nudged along the ray: a point on a border belongs to the next cell).
        let cell = vec2i(floor(start + t * dir + sign(dir) * 1e-3));
        let exits = box_exit(start, dir, vec2f(cell), vec2f(cell) + 1.0);
        let t_exit = min(min(exits.x, exits.y), 1.0);
        let t_sphere = t + radius / per_t;
        // Take the safe sphere step when it leaves the current cell; a shorter one (near the surface,
        // where radii shrink towards 0) would crawl, so solve the cell exactly instead.
        if admissible && t_sphere >= t_exit && radius > 0.0 {
            t = min(t_sphere, 1.0);
            continue;
        }
        let t_hit = cell_hit(cell, start, dir, t, t_exit);
        if t_hit >= 0.0 {
            return TraceResult(uv0 - span * t_hit, t_hit, fetch_count, is_grazing(v), 0u);
        }
        t = max(t, t_exit);
    }
    return TraceResult(uv0 - span * t, t, fetch_count, true, 0u);
}
