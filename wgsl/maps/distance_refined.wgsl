// Visibility-refined distance map (seed 000), one invocation per voxel; GPU twin of maptools.distance.refine.
// Inputs: raw distances to the solid superset S' (dsolid) and to the free-space superset F' (dfree), both exact
// at the voxel centres (distance.wgsl, pass_y mode 0), and the sampled cone directions (unit, +z = down).
// For each direction s: forward free path l_s = first L with lower(dS')(c + L s) <= eps + L*alpha (safe steps
// of the (1 + alpha)-Lipschitz gap), then a backward visibility test: (c, s) is occluded only if some sample
// c - L s has lower(dF') > eps + L*alpha. Value = max(euclid - eps, min over admissible l_s) - margin, >= 0.
// Loops: directions <= ndirs, forward <= FORWARD_STEPS, backward <= BACKWARD_SAMPLES.
// #include "common/border.wgsl"

const FORWARD_STEPS: u32 = 48u;     // = distance.REFINE_FORWARD_STEPS
const BACKWARD_SAMPLES: u32 = 24u;  // = distance.REFINE_BACKWARD_SAMPLES

struct Params {
    width: u32,
    height: u32,
    slices: u32,
    ndirs: u32,
    sx: f32,
    sy: f32,
    sz: f32,
    eps: f32,      // half voxel diagonal
    alpha: f32,    // covering angle of the direction set (radians)
    margin: f32,   // rounding margin subtracted at the end
    _pad: vec2f,
};

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> dsolid: array<f32>;
@group(0) @binding(2) var<storage, read> dfree: array<f32>;
@group(0) @binding(3) var<storage, read> dirs: array<vec4f>;
@group(0) @binding(4) var<storage, read_write> dst: array<f32>;

// Nearest-voxel lower bound of a 1-Lipschitz field given at voxel centres: value - distance to that centre.
fn lower_bound(free: bool, p: vec3f) -> f32 {
    let f = floor(p / vec3f(P.sx, P.sy, P.sz));
    let fk = clamp(f.z, 0.0, f32(P.slices - 1u));
    let c = (vec3f(f.x, f.y, fk) + 0.5) * vec3f(P.sx, P.sy, P.sz);
    let i = wrap_index(i32(f.x), i32(P.width));
    let j = wrap_index(i32(f.y), i32(P.height));
    let idx = (u32(fk) * P.height + u32(j)) * P.width + u32(i);
    var v: f32;
    if (free) { v = dfree[idx]; } else { v = dsolid[idx]; }
    return v - length(p - c);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    if (gid.x >= P.width || gid.y >= P.height || gid.z >= P.slices) { return; }
    let out_index = (gid.z * P.height + gid.y) * P.width + gid.x;
    let euclid = dsolid[out_index];
    if (euclid <= P.eps) {
        dst[out_index] = 0.0;
        return;
    }
    let c = (vec3f(gid) + 0.5) * vec3f(P.sx, P.sy, P.sz);
    let bstep_min = 0.5 * min(P.sx, min(P.sy, P.sz));
    var best = 3.0e38;
    var found = false;
    for (var n = 0u; n < P.ndirs; n++) {
        let s = dirs[n].xyz;
        var L = 0.0;
        for (var step = 0u; step < FORWARD_STEPS; step++) {
            let g = lower_bound(false, c + L * s) - P.eps - L * P.alpha;
            if (g <= 0.0 || L >= best) { break; }
            L += g / (1.0 + P.alpha);
        }
        if (L >= best) { continue; }
        let lend = c.z / s.z;
        let bstep = max(lend / f32(BACKWARD_SAMPLES), bstep_min);
        var occluded = false;
        for (var q = 1u; q <= BACKWARD_SAMPLES; q++) {
            let lb = f32(q) * bstep;
            if (lb > lend) { break; }
            if (lower_bound(true, c - lb * s) > P.eps + lb * P.alpha) {
                occluded = true;
                break;
            }
        }
        if (!occluded) {
            best = L;
            found = true;
        }
    }
    var v = euclid - P.eps;
    if (found) { v = max(v, best); }
    dst[out_index] = max(v - P.margin, 0.0);
}
