// Texture coordinate of x ∈ [0, 1] on a pre-integration table axis of n entries, entry i
// standing for i / (n − 1) (render_core::preintegration): the coordinate of texel centres, so
// a filtered sample interpolates between the two entries around x as Table3d::sample does.
// Shared by every renderer that samples a table_texture (render_core::table_texture::TABLE_WGSL).
fn table_coord(x: f32, n: f32) -> f32 {
    return (clamp(x, 0.0, 1.0) * (n - 1.0) + 0.5) / n;
}
