// The vertex stage of a fullscreen pass: one triangle covering the target (draw 3 vertices), so a fragment entry
// runs once per target pixel. The viewer's error view and its present copy draw with it.

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    let p = vec2f(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4f(p * 2.0 - 1.0, 0.0, 1.0);
}
