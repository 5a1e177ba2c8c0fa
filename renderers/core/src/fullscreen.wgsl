// A triangle that covers the whole viewport (vertices 0, 1, 2 at clip (-1, -1), (3, -1),
// (-1, 3)), for passes that run a fragment shader once per pixel: no vertex buffer.
@vertex
fn fullscreen_vs(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let x = f32((vi << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(vi & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.5, 1.0);
}
