// Rasterisation entry points: vertex transform, then per fragment the technique's `trace`, the texture
// filter's lookups at the hit and the thesis' shading model (ambient 0.2 * albedo, Lambert diffuse,
// Blinn-Phong 0.2 * pow(., 32)). Composed after the generated interfaces (MAX_LIGHTS among them), one technique
// file, one filter (`filter_texture`), one derivative source (`texture_derivatives`) and one shading_normal
// snippet, one shadow snippet (`light_visibility`, shadows/MODE.wgsl) and the material variant's constants
// (RELIEF_CLAMP) (wgpuviewer/relief/shaders.py). The Frame, Light and Object structs are generated from shaders.FRAME
// and shaders.OBJECT; DataOut and DataOutHitDepth from renderer.DATA_OUT.
// #include "common/heat.wgsl"
// #include "common/footprint.wgsl"

// Frame.mode values of fs_color (the window; renderer.MODES); offscreen rendering reads fs_data's raw targets
// instead, whose colour follows MODE_ALBEDO too.
const MODE_COLOR: u32 = 0u;
const MODE_COST: u32 = 1u;
const MODE_UV: u32 = 2u;
const MODE_LAYER_DEPTH: u32 = 3u;  // the hit's layer depth t in the relief, 0 = top
const MODE_LAYERS: u32 = 4u;
const MODE_ALBEDO: u32 = 5u;  // the filtered albedo, unlit (the filtering study compares it)

@group(0) @binding(0) var<uniform> frame: Frame;
@group(2) @binding(0) var<uniform> object: Object;

struct VertexIn {
    @location(0) position: vec3f,
    @location(1) normal: vec3f,
    @location(2) tangent: vec4f,  // w: handedness of the bitangent
    @location(3) uv: vec2f,
}

struct VertexOut {
    @builtin(position) clip: vec4f,
    @location(0) world_pos: vec3f,
    @location(1) normal: vec3f,
    @location(2) tangent: vec4f,
    @location(3) uv: vec2f,
    // The frame's values that steer the fragment shader's branches reach it as flat inputs, not as uniform loads:
    // Mesa 22's lavapipe recompiles a fragment shader whose branches read a uniform buffer each time that buffer is
    // rebound with new values (every frame), and keeps every copy (0.6-24 MB and up to 0.1 s a frame). A storage
    // buffer avoids that too, but llvmpipe then runs the ray searches up to 30x slower.
    @location(4) @interpolate(flat) mode: u32,
    @location(5) @interpolate(flat) light_count: u32,
}

@vertex
fn vs_main(in: VertexIn) -> VertexOut {
    var out: VertexOut;
    let world = object.model * vec4f(in.position, 1.0);
    out.clip = frame.view_proj * world;
    out.world_pos = world.xyz;
    out.normal = (object.normal_matrix * vec4f(in.normal, 0.0)).xyz;
    out.tangent = vec4f((object.model * vec4f(in.tangent.xyz, 0.0)).xyz, in.tangent.w);
    // glTF's KHR_texture_transform order: scale, then offset (only its fraction: the renderer drops whole tiles)
    out.uv = in.uv * object.uv_transform.xy + object.uv_transform.zw;
    out.mode = frame.mode;
    out.light_count = frame.light_count;
    return out;
}

struct Shaded {
    color: vec3f,
    hit: TraceResult,
}

// Clip position of a traced hit. The hit lies hit.uv - in.uv (uv units) along the surface and its layer depth
// times height_scale below it, in the tangent frame scaled by the world units per uv unit here (the relief is
// traced in uv units). Only the outputs that show it call it: the window's colour path skips its derivatives.
fn hit_clip(in: VertexOut, hit: TraceResult) -> vec4f {
    let duv_dx = dpdx(in.uv);
    let duv_dy = dpdy(in.uv);
    // the square root of the areas a pixel covers in the world and in uv
    let world_area = length(cross(dpdx(in.world_pos), dpdy(in.world_pos)));
    let world_per_uv = sqrt(world_area / max(abs(duv_dx.x * duv_dy.y - duv_dx.y * duv_dy.x), 1e-30));
    let n_geo = normalize(in.normal);
    let t_geo = normalize(in.tangent.xyz - n_geo * dot(n_geo, in.tangent.xyz));
    let b_geo = cross(n_geo, t_geo) * in.tangent.w;
    let duv = hit.uv - in.uv;
    let below = hit.depth * trace_params.height_scale;
    let p = in.world_pos + world_per_uv * (t_geo * duv.x + b_geo * duv.y - n_geo * below);
    return frame.view_proj * vec4f(p, 1.0);
}

// Camera depth of a traced hit: its distance from the camera along the view axis (the clip w of the
// perspective projection), in scene units.
fn hit_view_depth(in: VertexOut, hit: TraceResult) -> f32 {
    return hit_clip(in, hit).w;
}

// The depth buffer's value at a traced hit (depth_offset materials): reversed Z (camera.perspective), so a hit
// below the surface is farther, and other geometry between the surface and the hit shows through.
fn hit_frag_depth(in: VertexOut, hit: TraceResult) -> f32 {
    let clip = hit_clip(in, hit);
    return clamp(clip.z / max(clip.w, 1e-30), 0.0, 1.0);
}

// The derivative source's raw length ratio of this fragment (the `filter` target's w).
var<private> filter_ratio: f32;

fn shade(in: VertexOut) -> Shaded {
    // Derivatives and mip level come from the unperturbed UV, before any non-uniform control flow:
    // they do not jump where the traced UV does (silhouettes, tiling seams).
    let duv_dx = dpdx(in.uv);
    let duv_dy = dpdy(in.uv);
    let texels = vec2f(f32(trace_params.depth_width), f32(trace_params.depth_height));
    let footprint = max(dot(duv_dx * texels, duv_dx * texels), dot(duv_dy * texels, duv_dy * texels));
    let lod = max(0.5 * log2(max(footprint, 1e-12)), 0.0);
    pixel_footprint = mat2x2f(duv_dx, duv_dy);

    let n_geo = normalize(in.normal);
    let t_geo = normalize(in.tangent.xyz - n_geo * dot(n_geo, in.tangent.xyz));
    let b_geo = cross(n_geo, t_geo) * in.tangent.w;
    let to_eye = normalize(frame.camera_pos.xyz - in.world_pos);
    let v_ts = vec3f(dot(to_eye, t_geo), dot(to_eye, b_geo), dot(to_eye, n_geo));

    // The search runs on the uv's fraction (exact in float32): under repeat addressing the same texels, but each
    // step resolved at magnitude < 1 rather than at the tile count (POM's fixed steps would round there). The whole
    // tiles go back onto the hit, so it stays continuous across tile seams for the derivatives below. Clamp
    // addressing has one tile, the uv square.
    let tile = select(floor(in.uv), vec2f(0.0), RELIEF_CLAMP);
    var hit = trace(in.uv - tile, v_ts, lod);
    let traced_uv = hit.uv;
    hit.uv += tile;
    // The filters' footprint: derivatives from the draw's source, taken here, in uniform control flow.
    let derivs = texture_derivatives(in.uv, v_ts, hit);
    filter_stats.flags = derivs.flags;
    filter_ratio = derivs.ratio;
    // Clamp addressing: the uv square is the relief's extent; a hit outside it means the ray left the relief
    // through its side before meeting it (the segment from an entry inside the square to a hit inside stays in
    // it): a silhouette. Repeat addressing tiles the relief on past the face's edge.
    if RELIEF_CLAMP && (any(hit.uv < vec2f(0.0)) || any(hit.uv > vec2f(1.0))) {
        discard;
    }

    let fp = Footprint(hit.uv, derivs.dx, derivs.dy, v_ts, lod);
    let albedo = filter_texture(albedo_tex, fp).rgb;
    if in.mode == MODE_ALBEDO {
        return Shaded(albedo, hit);
    }
    let n = shading_normal(fp);
    var color = 0.2 * albedo;
    for (var i = 0u; i < min(in.light_count, MAX_LIGHTS); i++) {
        let light = frame.lights[i];
        var to_light = light.vector.xyz;
        var radiance = light.color.rgb;
        if light.vector.w > 0.5 {
            let offset = light.vector.xyz - in.world_pos;
            to_light = offset;
            radiance /= 1.0 + dot(offset, offset);  // bounded falloff, no singularity at the light
        }
        let l_world = normalize(to_light);
        let l = vec3f(dot(l_world, t_geo), dot(l_world, b_geo), dot(l_world, n_geo));
        let diffuse = max(dot(l, n), 0.0) * albedo;
        let specular = 0.2 * pow(max(dot(n, normalize(l + v_ts)), 0.0), 32.0);
        color += (diffuse + specular) * radiance * light_visibility(traced_uv, hit.depth, l, lod);
    }
    hit.fetches += shadow_fetches;  // the cost of the shadow rays, shown with the view ray's
    return Shaded(color, hit);
}

// The thesis' debug view: layer count as grey, (N - Nmin) / (Nmax - Nmin) for techniques with a layer
// range (pom_adaptive), N / layers for fixed layer counts; black for techniques without layers.
fn layer_grey(n: u32) -> f32 {
    return clamp((f32(n) - frame.layer_lo) / max(frame.layer_hi - frame.layer_lo, 1.0), 0.0, 1.0);
}

// Window/surface output: one target, the Frame.mode decides what is shown.
fn fs_color_of(in: VertexOut, s: Shaded) -> vec4f {
    switch in.mode {
        case MODE_COST: { return vec4f(heat(f32(s.hit.fetches) / frame.cost_scale), 1.0); }
        case MODE_UV: { return vec4f(fract(s.hit.uv), 0.0, 1.0); }
        case MODE_LAYER_DEPTH: { return vec4f(vec3f(s.hit.depth), 1.0); }
        case MODE_LAYERS: { return vec4f(vec3f(layer_grey(s.hit.layers)), 1.0); }
        // nearer is brighter, with no range to know: 1 / (1 + distance)
        default: { return vec4f(s.color, 1.0); }
    }
}

@fragment
fn fs_color(in: VertexOut) -> @location(0) vec4f {
    return fs_color_of(in, shade(in));
}

// The window's camera-depth view (renderer.MODES["depth"]): its own entry point, because the derivatives it takes
// would cost every other mode of fs_color their time even where the mode skips them (llvmpipe: +11 ms a frame at
// 480x270). Nearer is brighter, with no range to know: 1 / (1 + distance).
@fragment
fn fs_view_depth(in: VertexOut) -> @location(0) vec4f {
    return view_depth_color(in, shade(in));
}

fn view_depth_color(in: VertexOut, s: Shaded) -> vec4f {
    return vec4f(vec3f(1.0 / (1.0 + max(hit_view_depth(in, s.hit), 0.0))), 1.0);
}

// Offscreen output: the shaded colour plus the raw trace data (uv/depth/cost modes, .npy files). DataOut is
// generated from the renderer's offscreen targets (wgpuviewer/relief/renderer.py, DATA_OUT): color; data: hit u,
// hit v, hit layer depth, fetches (negative: capped) as float bits; layers: depth layers the search used; filtering:
// texels the filter read, depth fetches of its visibility traces and slopes, hidden texels | flags << 24, the
// derivative source's raw length ratio as float bits (FilterStats, common/footprint.wgsl); view_depth: the hit's
// camera depth as float bits.
fn data_out(in: VertexOut, s: Shaded) -> DataOut {
    let fetches = f32(s.hit.fetches);
    let data = vec4f(s.hit.uv, s.hit.depth, select(fetches, -fetches - 1.0, s.hit.capped));
    let stats = vec4u(filter_stats.texels, filter_stats.depth_fetches,
                      min(filter_stats.hidden, 0xffffffu) | (filter_stats.flags << 24u), bitcast<u32>(filter_ratio));
    return DataOut(vec4f(s.color, 1.0), bitcast<vec4u>(data), s.hit.layers, stats, bitcast<u32>(hit_view_depth(in, s.hit)));
}

@fragment
fn fs_data(in: VertexOut) -> DataOut {
    return data_out(in, shade(in));
}

// The entry points of depth_offset materials: as above, and the hit's depth into the depth buffer. Writing
// frag_depth turns the early depth test off for the whole draw, so only those materials' pipelines use them.
struct ColorHitDepth {
    @location(0) color: vec4f,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_color_hit_depth(in: VertexOut) -> ColorHitDepth {
    let s = shade(in);
    return ColorHitDepth(fs_color_of(in, s), hit_frag_depth(in, s.hit));
}

@fragment
fn fs_view_depth_hit_depth(in: VertexOut) -> ColorHitDepth {
    let s = shade(in);
    return ColorHitDepth(view_depth_color(in, s), hit_frag_depth(in, s.hit));
}

@fragment
fn fs_data_hit_depth(in: VertexOut) -> DataOutHitDepth {
    let s = shade(in);
    let d = data_out(in, s);
    return DataOutHitDepth(d.color, d.data, d.layers, d.filtering, d.view_depth, hit_frag_depth(in, s.hit));
}
