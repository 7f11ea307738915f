// What a texture filter is given and what it reports (wgpuviewer/relief/filters.py; the generated filter
// interface declares FilterParams, the FLAG_* bits, VIS_TOLERANCE and DERIVATIVE_LIMIT).
// #include "common/trace.wgsl"

// A pixel's texture footprint: the traced hit, the screen-space derivatives of the uv there (UV units per
// pixel, from the derivative source), and for visibility traces the view vector and the trace's mip level.
struct Footprint {
    uv: vec2f,
    dx: vec2f,
    dy: vec2f,
    v: vec3f,
    lod: f32,
}

// What a derivative source (derivatives/*.wgsl) returns: the derivatives, how much longer the raw ones were
// than the unperturbed ones (the larger of the two axes; 1 for the unperturbed source), and FLAG_* bits.
struct Derivatives {
    dx: vec2f,
    dy: vec2f,
    ratio: f32,
    flags: u32,
}

// Per pixel, over all lookups (albedo and normal): texels the filter read (hardware samples counted as the
// texels they blend), depth fetches of visibility traces and analytic slopes, texels dropped as hidden, FLAG_*.
struct FilterStats {
    texels: u32,
    depth_fetches: u32,
    hidden: u32,
    flags: u32,
}

var<private> filter_stats: FilterStats;

// No NaN/inf in x (the exponent bits: compilers may fold x != x away).
fn finite2(x: vec2f) -> bool {
    return all((bitcast<vec2u>(x) & vec2u(0x7f800000u)) != vec2u(0x7f800000u));
}

// A footprint every filter can use: a non-finite uv or derivative becomes 0 (flagged nonfinite); finite
// values pass bit for bit.
fn sanitized(fp: Footprint) -> Footprint {
    var f = fp;
    if !finite2(f.uv) {
        f.uv = vec2f(0.0);
        filter_stats.flags |= FLAG_NONFINITE;
    }
    if !(finite2(f.dx) && finite2(f.dy)) {
        f.dx = vec2f(0.0);
        f.dy = vec2f(0.0);
        filter_stats.flags |= FLAG_NONFINITE;
    }
    return f;
}

// A derivative (UV units) no longer than the whole texture of `size` texels: a longer one would only pick
// the coarsest level anyway, and the texel loops must stay bounded (flagged huge).
fn texture_bounded(d: vec2f, size: vec2f) -> vec2f {
    let texels = length(d * size);
    let limit = max(size.x, size.y);
    if texels > limit {
        filter_stats.flags |= FLAG_HUGE;
        return d * (limit / texels);
    }
    return d;
}

// The footprint of a software filter: sanitized, both derivatives within the texture.
fn loop_footprint(fp: Footprint, size: vec2f) -> Footprint {
    var f = sanitized(fp);
    f.dx = texture_bounded(f.dx, size);
    f.dy = texture_bounded(f.dy, size);
    return f;
}

// The bound of the displaced and analytic sources: a derivative longer than DERIVATIVE_LIMIT times the
// unperturbed one (d0) is scaled down to that length (flagged bounded); a non-finite one becomes d0.
fn bounded_derivative(d: vec2f, d0: vec2f, out: ptr<function, Derivatives>) -> vec2f {
    let limit = DERIVATIVE_LIMIT * length(d0);
    if !finite2(d) {
        (*out).flags |= FLAG_NONFINITE;
        (*out).ratio = 3.0e38;
        return d0;
    }
    let len = length(d);
    (*out).ratio = max((*out).ratio, select(len / length(d0), select(1.0, 3.0e38, len > 0.0), length(d0) == 0.0));
    if len > limit {
        (*out).flags |= FLAG_BOUNDED;
        return d * (limit / len);
    }
    return d;
}

fn bounded_derivatives(dx: vec2f, dy: vec2f, d0x: vec2f, d0y: vec2f) -> Derivatives {
    var out = Derivatives(vec2f(0.0), vec2f(0.0), 0.0, 0u);
    out.dx = bounded_derivative(dx, d0x, &out);
    out.dy = bounded_derivative(dy, d0y, &out);
    return out;
}
