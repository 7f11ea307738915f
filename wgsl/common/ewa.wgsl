// Elliptical weighted average (Heckbert 1989) over a pixel's footprint, shared by ewa, ewa_vis and ewa_vis_rows;
// the float64 twin is wgpuviewer/studies/filtering/cpu.py (tests compare them texel for texel).
//
// At mip level L (texel coordinates x = u * W_L - 0.5) the footprint J_L = [dx dy] * size_L maps the pixel's
// unit circle to the ellipse with shape matrix J_L J_L^T. Weights exp(-alpha Q) - exp(-alpha), Q = x^T S^-1 x,
// a Gaussian of covariance S / (2 alpha), cut off at Q = 1. S = J_L J_L^T + (alpha / 3) I: the prefilter adds
// the variance (1/6 texel^2 per axis) of the bilinear tent through which the reference sees the texels
// (Heckbert adds 1, which blurs footprints of a few texels noticeably more), and keeps the ellipse at least
// sqrt(alpha / 3) > sqrt(1/2) texel wide, so it always holds a texel centre. In coefficients:
// Q(U, V) = (A U^2 + B U V + C V^2) / F with A = vx^2 + vy^2 + p, B = -2 (ux vx + uy vy), C = ux^2 + uy^2 + p,
// p = alpha / 3, F = A C - B^2 / 4.
// Level: log2 of the minor semi-axis (level-0 texels) minus 1, so the minor axis spans 2 to 4 texels of the level
// read (at the minor axis' own level, as pbrt chooses it, the mip chain's box prefilter blurs footprints of a few
// texels noticeably: measured in docs/filtering.md); levels floor and floor + 1 blended by the fraction; when
// their texel estimate (area pi sqrt(F) + 2 (sqrt(A) + sqrt(C)) + 1 each) exceeds max_texels, the level rises
// until it fits (flagged capped), and the loops stop after max_texels texels in any case.
// Visibility: texel_hidden (visibility/*.wgsl, chosen by the composer) tests a texel centre. The full method tests
// every texel; the rows method (the cheap one of Romanyuk & Dudnyk 2017) walks each row from its left end until a
// hidden texel, then from its right end back until a hidden texel, and drops the texels between without testing
// them. A level whose texels are all hidden falls back to the bilinear value at the hit, which is visible.
// Weighting of a hidden texel (the visibility filters' `inherit`): dropped, or inherited by its substitute (the
// level's texel whose cell holds the point where the texel's ray meets the relief) when that substitute lies
// outside the ellipse; one inside is a texel of the footprint, which the walk itself counts or drops, once.
// #include "common/ellipse.wgsl"
// #include "common/wrap.wgsl"

struct EwaLevel {
    level: i32,
    size: vec2i,
    centre: vec2f,  // the hit in level-L texel coordinates
    a: f32,         // Q = a U^2 + b U V + c V^2 (coefficients already divided by F)
    b: f32,
    c: f32,
    half: vec2f,    // the ellipse lies within |U| <= half.x, |V| <= half.y
    area: f32,      // pi sqrt(F)
}

// Size of mip level `level`: max(1, floor(size / 2^level)), as WebGPU defines it. Computed, not queried:
// textureDimensions with a level that differs between invocations returned level 0's size on lavapipe.
fn level_size(tex: texture_2d<f32>, level: i32) -> vec2i {
    return max(vec2i(textureDimensions(tex, 0)) >> vec2u(u32(level)), vec2i(1));
}

fn ewa_alpha() -> f32 {
    return clamp(filter_params.alpha, ALPHA_MIN, ALPHA_MAX);
}

fn ewa_level(tex: texture_2d<f32>, fp: Footprint, level: i32) -> EwaLevel {
    let size = level_size(tex, level);
    let s = vec2f(size);
    let e = ellipse_coefficients(fp.dx * s, fp.dy * s);
    let prefilter = ewa_alpha() / 3.0;
    let a = e.a + prefilter;
    let c = e.c + prefilter;
    let f = a * c - 0.25 * e.b * e.b;
    return EwaLevel(level, size, fp.uv * s - 0.5, a / f, e.b / f, c / f, vec2f(sqrt(c), sqrt(a)), 3.14159265 * sqrt(f));
}

fn ewa_estimate(e: EwaLevel) -> f32 {
    return e.area + 2.0 * (e.half.x + e.half.y) + 1.0;
}

struct EwaSum {
    value: vec4f,
    weight: f32,
    visited: u32,  // texels inside the ellipse taken so far, read or found hidden (both levels)
    texels: u32,   // texels read so far
    budget: u32,   // max_texels: most texels visited per lookup
}

// Q of texel (i, j) of level e: inside the ellipse below 1.
fn ewa_q(e: EwaLevel, texel: vec2i) -> f32 {
    let d = vec2f(texel) - e.centre;
    return e.a * d.x * d.x + e.b * d.x * d.y + e.c * d.y * d.y;
}

// Weight w of a hidden texel whose ray meets the relief at `occluder` (uv), inherited by its substitute: the
// texel of level e whose cell holds that point, unless it lies inside the ellipse (a footprint texel: the walk
// counts it with its own weight or drops it).
fn ewa_substitute(tex: texture_2d<f32>, e: EwaLevel, occluder: vec2f, w: f32, acc: ptr<function, EwaSum>) {
    let texel = vec2i(floor(occluder * vec2f(e.size)));
    if ewa_q(e, texel) < 1.0 {
        return;
    }
    (*acc).value += w * textureLoad(tex, wrap_texel(texel, e.size), e.level);
    (*acc).weight += w;
    (*acc).texels += 1u;
}

// Texel (i, j) of level e: its weight added to `acc` unless it is hidden (returns true then; with `inherit` the
// weight goes to its substitute) or outside.
fn ewa_take(tex: texture_2d<f32>, fp: Footprint, e: EwaLevel, i: i32, j: i32, visibility: bool, inherit: bool,
            acc: ptr<function, EwaSum>) -> bool {
    let q = ewa_q(e, vec2i(i, j));
    if q >= 1.0 {
        return false;  // a row end just outside (rounding)
    }
    (*acc).visited += 1u;
    let alpha = ewa_alpha();
    let w = exp(-alpha * q) - exp(-alpha);
    var occluder = vec2f(0.0);
    if visibility && texel_hidden((vec2f(f32(i), f32(j)) + 0.5) / vec2f(e.size), fp, &occluder) {
        filter_stats.hidden += 1u;
        if inherit {
            ewa_substitute(tex, e, occluder, w, acc);
        }
        return true;
    }
    (*acc).value += w * textureLoad(tex, wrap_texel(vec2i(i, j), e.size), e.level);
    (*acc).weight += w;
    (*acc).texels += 1u;
    return false;
}

fn ewa_full(acc: ptr<function, EwaSum>) -> bool {
    if (*acc).visited >= (*acc).budget {
        filter_stats.flags |= FLAG_CAPPED;
        return true;
    }
    return false;
}

// The weighted average of `acc`; when nothing had weight (everything hidden) the bilinear value at the hit,
// which is visible.
fn ewa_result(tex: texture_2d<f32>, fp: Footprint, e: EwaLevel, acc: ptr<function, EwaSum>) -> vec4f {
    if (*acc).weight <= 0.0 {
        return textureSampleLevel(tex, filter_sampler, fp.uv, f32(e.level));
    }
    return (*acc).value / (*acc).weight;
}

// The weighted average over level e; rows: Romanyuk & Dudnyk 2017's row-ends method, inherit: hidden texels'
// weights go to their substitutes (both for the visibility filters only).
fn ewa_average(tex: texture_2d<f32>, fp: Footprint, e: EwaLevel, visibility: bool, rows: bool, inherit: bool,
               acc: ptr<function, EwaSum>) -> vec4f {
    (*acc).value = vec4f(0.0);
    (*acc).weight = 0.0;
    let j0 = i32(ceil(e.centre.y - e.half.y));
    let j1 = i32(floor(e.centre.y + e.half.y));
    var done = false;
    for (var j = j0; j <= j1 && j - j0 < i32(MAX_TEXELS_MAX) && !done; j++) {
        let y = f32(j) - e.centre.y;
        let disc = e.b * e.b * y * y - 4.0 * e.a * (e.c * y * y - 1.0);
        if disc > 0.0 {
            let root = sqrt(disc);
            let i0 = i32(ceil(e.centre.x + (-e.b * y - root) / (2.0 * e.a)));
            let i1 = i32(floor(e.centre.x + (-e.b * y + root) / (2.0 * e.a)));
            var stop = i1 + 1;  // where the forward walk met a hidden texel (rows method)
            for (var i = i0; i <= i1 && !done; i++) {
                if ewa_full(acc) {
                    done = true;
                } else if ewa_take(tex, fp, e, i, j, visibility, inherit, acc) && rows {
                    stop = i;
                    break;
                }
            }
            if rows && stop <= i1 && !done {
                var back = i1;
                for (; back > stop && !done; back--) {
                    if ewa_full(acc) {
                        done = true;
                    } else if ewa_take(tex, fp, e, back, j, visibility, inherit, acc) {
                        break;
                    }
                }
                if !done {
                    filter_stats.hidden += u32(max(back - stop - 1, 0));  // dropped between the two hidden texels
                }
            }
        }
    }
    return ewa_result(tex, fp, e, acc);
}

fn ewa(tex: texture_2d<f32>, footprint: Footprint, visibility: bool, rows: bool, inherit: bool) -> vec4f {
    let size0 = vec2f(textureDimensions(tex, 0));
    let fp = loop_footprint(footprint, size0);
    let axes = footprint_axes(fp.dx * size0, fp.dy * size0);
    let top = i32(textureNumLevels(tex)) - 1;
    let lod = clamp(log2(max(axes.minor, 1e-8)) - 1.0, 0.0, f32(top));
    var level = i32(floor(lod));
    var frac = lod - f32(level);
    let budget = clamp(filter_params.max_texels, MAX_TEXELS_MIN, MAX_TEXELS_MAX);
    var acc = EwaSum(vec4f(0.0), 0.0, 0u, 0u, budget);
    for (var k = 0; k < 32 && level < top; k++) {
        var estimate = ewa_estimate(ewa_level(tex, fp, level));
        if frac > 0.0 {
            estimate += ewa_estimate(ewa_level(tex, fp, level + 1));
        }
        if estimate <= f32(budget) {
            break;
        }
        level += 1;
        frac = 0.0;
        filter_stats.flags |= FLAG_CAPPED;
    }
    var value = ewa_average(tex, fp, ewa_level(tex, fp, level), visibility, rows, inherit, &acc);
    if frac > 0.0 && level < top {
        let next = ewa_average(tex, fp, ewa_level(tex, fp, level + 1), visibility, rows, inherit, &acc);
        value = mix(value, next, frac);
    }
    filter_stats.texels += acc.texels;
    return value;
}
