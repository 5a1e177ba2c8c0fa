// Texel `i` of layer `layer` of a render_core::texel_texture (TEXEL_ROW = 8192 texels a row:
// the address is a mask and a shift).
fn texel_at(t: texture_2d_array<u32>, layer: u32, i: u32) -> vec4<u32> {
    return textureLoad(t, vec2<i32>(i32(i & 8191u), i32(i >> 13u)), i32(layer), 0);
}
