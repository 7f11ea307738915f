// Distance-map parallax (Donnelly), shared by `distance` and `distance_refined`: the loop is the same, only the
// texture bound at distance_tex differs. The plain map is one volume; the refined map (Romanyuk et al. 2017) is one
// volume per bin of ray directions (azimuth sector x polar band, maptools/kinds/distance_refined/) and the plain volume last,
// stacked along the texture's depth. A ray keeps its direction, so it picks its volume once: by the azimuth of its
// horizontal direction and its polar angle, or the last (plain) volume when it is steeper than the binned cone.
//
// Metric (docs/maps.md): X = u * W, Y = v * W, Z = t * S * W, one unit = one texel along u. A volume stores per
// voxel a radius that a NEAREST lookup anywhere in the voxel may step without reaching the relief (for a bin's
// volume: along any ray of that bin). The ray moves per unit t by |(span, S)| * W in that metric, so a radius r is
// a step of r / that in t. Where that step would not even leave the current bilinear cell (close to the surface
// radii shrink towards 0 and sphere tracing crawls), the cell is solved exactly (cell_hit, common/cell.wgsl) and
// left at its exit if it holds no hit: the tracer never passes through a surface and its hit is exact to float32.
// The search starts at the map's shallowest depth (depth_min): above it the ray meets nothing.
// A grazing ray skims the relief: its radii stay short and it advances a cell or two per step. After handover_steps
// such slow steps (common/maxmip_walk.wgsl's slow_step) it finishes with the max-pyramid walk from where it is
// (common/maxmip_walk.wgsl, at most pyramid_steps steps), which skips whole nodes the ray passes above.
// Bounded by `iterations` and pyramid_steps (capped rays are flagged and stop short of the surface, never behind it).
// #include "common/cell.wgsl"
// #include "common/maxmip_walk.wgsl"
// #include "common/wrap.wgsl"

const PI: f32 = 3.14159265358979;
// The volume a ray with span `span` (parallax_span) reads, as maptools.kinds.distance_refined.cpu.volume_index decides it:
// trace_params.sectors (azimuth sectors), bands (polar bands, edge k at cos = steep_cos^(k / bands)), steep_cos (cosine
// of the binned cone's half-angle; -2: every ray is binned) and volumes describe the texture
// (techniques/shared.py, distance_fixed).
fn direction_volume(span: vec2f) -> i32 {
    let cos_polar = trace_params.height_scale / length(vec3f(span, trace_params.height_scale));
    if cos_polar < trace_params.steep_cos {
        return i32(trace_params.volumes) - 1;
    }
    let sectors = i32(trace_params.sectors);
    var sector = 0;
    let h = -span;  // horizontal part of the ray's direction (X and Y scale alike in the metric)
    if sectors > 1 && (h.x != 0.0 || h.y != 0.0) {
        sector = clamp(i32(floor((atan2(h.y, h.x) + PI) / (2.0 * PI) * f32(sectors))), 0, sectors - 1);
    }
    let bands = i32(trace_params.bands);
    var band = 0;
    if bands > 1 {
        band = clamp(i32(floor(f32(bands) * log(cos_polar) / log(trace_params.steep_cos))), 0, bands - 1);
    }
    return band * sectors + sector;
}

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let dims = vec3i(textureDimensions(distance_tex, 0));
    let slices = dims.z / i32(trace_params.volumes);
    let size = vec2f(dims.xy);
    let span = parallax_span(v);
    let first = direction_volume(span) * slices;
    let start = uv0 * size - 0.5;
    let dir = -span * size;
    let per_t = size.x * length(vec3f(span, trace_params.height_scale));
    let cap = clamp(trace_params.iterations, ITERATIONS_MIN, ITERATIONS_MAX);
    let cells_per_t = max(abs(dir.x), abs(dir.y));
    var t = relief_range(0.0).x;  // depth_min (common/trace.wgsl)
    var slow = 0u;
    for (var step = 0u; step < cap; step++) {
        if slow >= trace_params.handover_steps {
            return maxmip_walk(uv0, v, t, trace_params.pyramid_steps);
        }
        let texel = vec2i(floor((uv0 - span * t) * size));
        let k = clamp(i32(floor(t * f32(slices))), 0, slices - 1);
        fetch_count += 1u;
        let radius = textureLoad(distance_tex, vec3i(wrap_texel(texel, dims.xy), first + k), 0).r;
        // The cell the ray is in (nudged along the ray: a point on a border belongs to the next cell).
        let cell = vec2i(floor(start + t * dir + sign(dir) * 1e-3));
        let exits = box_exit(start, dir, vec2f(cell), vec2f(cell) + 1.0);
        let t_exit = min(min(exits.x, exits.y), 1.0);
        let t_sphere = t + radius / per_t;
        // Take the safe sphere step when it leaves the current cell; a shorter one (near the surface,
        // where radii shrink towards 0) would crawl, so solve the cell exactly instead.
        if t_sphere >= t_exit && radius > 0.0 {
            let t_next = min(t_sphere, 1.0);
            slow += slow_step(t, t_next, cells_per_t);
            t = t_next;
            continue;
        }
        let t_hit = cell_hit(cell, start, dir, t, t_exit);
        if t_hit >= 0.0 {
            return TraceResult(uv0 - span * t_hit, t_hit, fetch_count, is_grazing(v), 0u);
        }
        slow += slow_step(t, max(t, t_exit), cells_per_t);  // a solved cell: one cell further
        t = max(t, t_exit);
    }
    return TraceResult(uv0 - span * t, t, fetch_count, true, 0u);
}
