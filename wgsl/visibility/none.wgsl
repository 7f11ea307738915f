// Visibility without a traced relief (filters without visibility, techniques that do not trace depth): the
// surface is the plane, nothing in the footprint is hidden.

fn texel_hidden(uv: vec2f, fp: Footprint) -> bool {
    return false;
}
