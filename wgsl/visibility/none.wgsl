// Visibility without a traced relief (filters without visibility, techniques that do not trace depth): the
// surface is the plane, nothing in the footprint is hidden.

fn texel_hidden(uv: vec2f, fp: Footprint, occluder: ptr<function, vec2f>) -> bool {
    return false;
}
