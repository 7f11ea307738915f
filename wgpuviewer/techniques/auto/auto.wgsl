// auto: the error budget as a technique. Per pixel the view angle picks a bin (bin 0: tan(angle) < bin_tan0;
// then bins_per_octave bins per octave of tan(angle), the last one open-ended; grazing views take the last);
// max_error picks a budget level (the largest 2^(budget_log2_min + j) not above it). The table
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
    let budget = clamp(trace_params.max_error, MAX_ERROR_MIN, MAX_ERROR_MAX);
    let level = i32(clamp(floor(log2(budget)) - f32(trace_params.budget_log2_min), 0.0, f32(dims.y - 1)));
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
    var r: TraceResult;
    switch u32(choice.y) {
        case AUTO_BASIC: {
            r = untraced(uv0);
        }
        case AUTO_PARALLAX: {
            r = parallax_offset(uv0, v, lod, false);
        }
        case AUTO_POM: {
            r = pom_search(uv0, v, lod, 0.0, auto_layers(pick));
        }
        case AUTO_RELIEF: {
            let binary_steps = u32(clamp(choice.w, 0.0, f32(trace_params.binary_steps_max)));
            r = relief_search(uv0, v, lod, auto_layers(pick), binary_steps);
        }
        case AUTO_QUADMAX, default: {
            r = quadmax_search(uv0, v, i32(choice.z), trace_params.quadmax_steps);
        }
    }
    r.capped = r.capped || is_grazing(v);
    r.layers = u32(choice.x) + 1u;
    return r;
}
