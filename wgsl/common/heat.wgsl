// The heat ramp of the cost and error views, black -> red -> yellow -> white (wgpuviewer.core.color.heat is
// its CPU twin, for the HUD's legend).
fn heat(x: f32) -> vec3f {
    let s = clamp(x, 0.0, 1.0) * 3.0;
    return clamp(vec3f(s, s - 1.0, s - 2.0), vec3f(0.0), vec3f(1.0));
}
