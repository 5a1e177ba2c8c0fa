//! The CPU twin's passes per tile of a rendered frame: every pixel's ray walked on the host from
//! the frame's own peeling layers, spent as the passes mode spends them.

use crate::layout::MeshLayout;
use crate::passmap::passes_per_tile;
use crate::render::PassData;
use crate::step;

/// The passes each of `tiles`×`tiles` tiles of the frame `d` needs by the CPU twin: each
/// pixel's ray walked with [`step::walk_segments`] over `layout` (the mesh as the GPU holds it)
/// from the frame's peeling layers, then spent per layer in rounds of `k`
/// ([`passes_per_tile`]).
pub fn tile_passes(layout: &MeshLayout, d: &PassData, tiles: u32, k: u32) -> Vec<u32> {
    let segments: Vec<Vec<u32>> = (0..d.width * d.height)
        .map(|i| {
            let (x, y) = (i % d.width, i / d.width);
            let entries: Vec<_> = d.layers.iter().map(|l| l[i as usize]).collect();
            let (o, dir) = d.ray_frame.ray(x as f32 + 0.5, y as f32 + 0.5);
            step::walk_segments(layout, &entries, o, dir, d.bias, d.max_steps).1
        })
        .collect();
    passes_per_tile(&segments, d.width, tiles, d.tile_size, k)
}
