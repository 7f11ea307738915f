// Visibility of a footprint texel on a traced relief (Romanyuk & Dudnyk 2017 (filtering with parallax mapping)):
// the texel's surface point is (uv, D(uv)), D bilinear at level 0. The view ray that reaches it enters the surface
// at uv + D * P (P = V.xy / V.z * S, the pixel's view vector for the whole footprint); the technique's own `trace`
// follows that ray. The texel is hidden when the ray meets the relief first: hit depth < D - VIS_TOLERANCE. A
// capped trace proves nothing: the texel is kept (flagged vis_capped). With an exact technique (maxmip, distance)
// this is the float64 reference's test (wgpuviewer/studies/filtering/cpu.py, texel_visibility) to float32
// precision. A hidden texel's `occluder` is where its ray meets the relief (not wrapped): the substitute's place.

fn texel_hidden(uv: vec2f, fp: Footprint, occluder: ptr<function, vec2f>) -> bool {
    let d = textureSampleLevel(depth_tex, material_sampler, uv, 0.0).r;
    let hit = trace(uv + d * parallax_span(fp.v), fp.v, fp.lod);
    filter_stats.depth_fetches += hit.fetches + 1u;
    if hit.capped {
        filter_stats.flags |= FLAG_VIS_CAPPED;
        return false;
    }
    *occluder = hit.uv;
    return hit.depth < d - VIS_TOLERANCE;
}
