// auto: the error budget as a technique. Per pixel the view angle picks a bin (bin 0: tan(angle) < bin_tan0;
// then bins_per_octave bins per octave of tan(angle), the last one open-ended; grazing views take the last);
// the fragment's budget picks a budget level (the largest 2^(budget_log2_min + j) not above it: auto_budget). The table
// (autotable.py beside this file: measured by the probe on this material's height map) holds per (bin, level) the
// cheapest candidate within the budget: its index, method and two parameters (a POM or relief layer count holds at
// the bin's upper edge and is scaled with tan(angle) inside the bin: auto_layers). The candidates are the very code
// the techniques basic, parallax, pom, relief and quadmax run (common/*.wgsl). `layers` reports the chosen
// candidate (1-based, cheapest first) for the layers debug view. The table texel is not counted as a fetch.
// #include "common/binary.wgsl"
// #include "common/layer_march.wgsl"
// #include "common/parallax.wgsl"
// #include "common/quadmax.wgsl"

const AUTO_BASIC: u32 = 0u;
const AUTO_PARALLAX: u32 = 1u;
const AUTO_POM: u32 = 2u;
const AUTO_QUADMAX: u32 = 3u;
const AUTO_RELIEF: u32 = 4u;

// The table texel for a view (texel: candidate index, method, the method's parameter (POM layers, relief linear
// steps, quadmax top_offset), relief's binary steps), with the view's bin, the table's bin count and tan(angle) for
// the layer count.
struct AutoPick {
    texel: vec4f,
    bin: i32,
    bins: i32,
    tan_view: f32,
}

// The fragment's error budget in texels: max_error, or where max_error_px > 0 and the pixel's footprint is known
// (pixel_footprint, common/trace.wgsl) the larger of it and the texels that max_error_px pixels span along the ray's
// direction on the map (every hit of the ray lies on that line, so its error does too): max_error_px |det J| / |adj(J) d|
// for J the footprint in texels per pixel and d the unit direction of the ray's uv in texels. So a minified surface
// (many texels per pixel) gets a larger budget and a magnified one keeps max_error; a degenerate footprint (det 0,
// a face seen edge-on) gives 0 and keeps it too. autotable.fragment_budget is its float64 twin.
fn auto_budget(v: vec3f) -> f32 {
    let budget = clamp(trace_params.max_error, MAX_ERROR_MIN, MAX_ERROR_MAX);
    let px = clamp(trace_params.max_error_px, MAX_ERROR_PX_MIN, MAX_ERROR_PX_MAX);
    let texels = vec2f(f32(trace_params.depth_width), f32(trace_params.depth_height));
    let jx = pixel_footprint[0] * texels;
    let jy = pixel_footprint[1] * texels;
    let along = v.xy * texels;
    let d = select(vec2f(1.0, 0.0), normalize(along), dot(along, along) > 1e-30);
    let det = abs(jx.x * jy.y - jx.y * jy.x);
    let adj = vec2f(jy.y * d.x - jy.x * d.y, jx.x * d.y - jx.y * d.x);  // adj(J) d: pixels per texel along d, times det
    let screen = px * det / max(length(adj), 1e-30);
    return max(budget, select(0.0, screen, px > 0.0 && det > 0.0));
}

fn auto_pick(v: vec3f) -> AutoPick {
    let dims = vec2i(textureDimensions(auto_table_tex, 0));  // (bins, budget levels)
    var bin = dims.x - 1;
    var tan_view = 0.0;
    if !is_grazing(v) {
        tan_view = length(v.xy) / v.z;
        if tan_view < trace_params.bin_tan0 {
            bin = 0;
        } else {
            let b = floor(f32(trace_params.bins_per_octave) * log2(tan_view / trace_params.bin_tan0)) + 1.0;
            bin = i32(clamp(b, 0.0, f32(dims.x - 1)));
        }
    }
    let level = i32(clamp(floor(log2(auto_budget(v))) - f32(trace_params.budget_log2_min), 0.0, f32(dims.y - 1)));
    return AutoPick(textureLoad(auto_table_tex, vec2i(bin, level), 0), bin, dims.x, tan_view);
}

// POM's layer count and relief's linear steps: the table's count n holds at the upper edge of the bin; below it the
// count that keeps the layers' horizontal spacing (what decides which features a layer steps over),
// ceil(n tan / tan_hi), down to ceil(n 2^(-1/k)) at the lower edge, where the table measured exactly that count
// (autotable.py scaled_layers). Bin 0 and the open-ended last bin run n as it is.
fn auto_layers(pick: AutoPick) -> u32 {
    let n = clamp(pick.texel.z, 1.0, f32(MAX_LAYERS));
    if pick.bin < 1 || pick.bin >= pick.bins - 1 {
        return u32(n);
    }
    let tan_hi = trace_params.bin_tan0 * exp2(f32(pick.bin) / f32(trace_params.bins_per_octave));
    return u32(clamp(ceil(n * pick.tan_view / tan_hi), 1.0, n));
}

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let pick = auto_pick(v);
    let choice = pick.texel;
    // Each method runs under its USES_ constant (relief.shaders.path_constants): a material's module compiles only
    // the methods its table picks (autotable.paths_used); one it leaves out is never chosen, its result flagged.
    var r = untraced(uv0);
    r.capped = true;
    switch u32(choice.y) {
        case AUTO_BASIC: {
            if USES_BASIC {
                r = untraced(uv0);
            }
        }
        case AUTO_PARALLAX: {
            if USES_PARALLAX {
                r = parallax_offset(uv0, v, lod, false);
            }
        }
        case AUTO_POM: {
            if USES_POM {
                r = pom_search(uv0, v, lod, 0.0, auto_layers(pick));
            }
        }
        case AUTO_RELIEF: {
            if USES_RELIEF {
                let binary_steps = u32(clamp(choice.w, 0.0, f32(trace_params.binary_steps_max)));
                r = relief_search(uv0, v, lod, auto_layers(pick), binary_steps);
            }
        }
        case AUTO_QUADMAX, default: {
            // A one-trip loop, not an `if`: llvmpipe runs a branch no lane takes with every lane masked, and the
            // quadmax walk's nested loops are the costliest of them; as a loop it costs fragments that do not take it
            // about a third less (showcase, 160x90: 128 -> 84-91 ms a frame, measured side by side).
            for (var once = 0u; once < select(0u, 1u, USES_QUADMAX); once++) {
                r = quadmax_search(uv0, v, i32(choice.z), trace_params.quadmax_steps);
            }
        }
    }
    r.capped = r.capped || is_grazing(v);
    r.layers = u32(choice.x) + 1u;
    return r;
}
