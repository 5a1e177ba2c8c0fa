//! The pass-count map (the paper's Fig. 5): every tile filled with a colour for the number of
//! ray-casting passes it ran, brighter where a ray entered the mesh, with dark tile borders;
//! the same counts as numbers ([`tile_counts`]); and the CPU twin of that count
//! ([`passes_per_tile`]; from a rendered frame's peeling layers, [`crate::twin::tile_passes`]).

use render_core::{Image, TileCounts};

/// A perceptually ordered ramp (dark blue → teal → yellow), sRGB stops.
const RAMP: [[f32; 3]; 5] = [
    [0.10, 0.08, 0.35],
    [0.15, 0.35, 0.60],
    [0.15, 0.60, 0.55],
    [0.55, 0.80, 0.30],
    [0.99, 0.90, 0.15],
];

fn ramp(x: f32) -> [f32; 3] {
    let x = x.clamp(0.0, 1.0) * (RAMP.len() - 1) as f32;
    let i = (x.floor() as usize).min(RAMP.len() - 2);
    let t = x - i as f32;
    std::array::from_fn(|c| RAMP[i][c] + t * (RAMP[i + 1][c] - RAMP[i][c]))
}

fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// The map for a `width`×`height` view cut into `tiles`×`tiles` tiles of `tile_w`×`tile_h`
/// pixels: `passes[tile]` per tile (row-major), `entered[pixel]` where a ray hit the mesh.
pub fn pass_map(
    width: u32,
    height: u32,
    tiles: u32,
    tile_size: [u32; 2],
    passes: &[u32],
    entered: &[bool],
) -> Image {
    let max = passes.iter().copied().max().unwrap_or(0).max(1) as f32;
    let mut img = Image::new(width, height);
    for y in 0..height {
        for x in 0..width {
            let (tx, ty) = (x / tile_size[0], y / tile_size[1]);
            let t = (ty * tiles + tx) as usize;
            let p = passes.get(t).copied().unwrap_or(0);
            let border = x % tile_size[0] == 0 || y % tile_size[1] == 0;
            let mut c = if p == 0 {
                [0.05; 3]
            } else {
                ramp(p as f32 / max)
            };
            let hit = entered[(y * width + x) as usize];
            let scale = if border {
                0.2
            } else if hit {
                1.0
            } else {
                0.45
            };
            c = c.map(|v| v * scale);
            let l = c.map(srgb_to_linear);
            img.set(x, y, [l[0], l[1], l[2], 1.0]);
        }
    }
    img
}

/// The passes each tile of a `width`×`height` view cut into `tiles`×`tiles` tiles of
/// `tile_size` pixels needs when it spends them as the paper does (§2.3, §3.2 phases 3a–3b):
/// per peeling layer, rounds of `k` passes until a count after a round finds none of the
/// tile's rays still inside the mesh, then the next layer. `segments[pixel]` holds the steps
/// of each stretch of that pixel's ray, one per layer it walked from, in order
/// ([`crate::step::walk_segments`]). A tile's count is thus, summed over the stretches, the
/// longest stretch of that rank among its pixels rounded up to a multiple of `k`; a tile no
/// ray enters needs none. Row-major, like the renderer's per-tile counts.
pub fn passes_per_tile(
    segments: &[Vec<u32>],
    width: u32,
    tiles: u32,
    tile_size: [u32; 2],
    k: u32,
) -> Vec<u32> {
    // The longest stretch of each rank, per tile.
    let mut longest: Vec<Vec<u32>> = vec![Vec::new(); (tiles * tiles) as usize];
    for (i, segs) in segments.iter().enumerate() {
        let (x, y) = (i as u32 % width, i as u32 / width);
        let tile = &mut longest[((y / tile_size[1]) * tiles + x / tile_size[0]) as usize];
        if tile.len() < segs.len() {
            tile.resize(segs.len(), 0);
        }
        for (l, &s) in tile.iter_mut().zip(segs) {
            *l = (*l).max(s);
        }
    }
    longest
        .iter()
        .map(|l| l.iter().map(|&s| s.div_ceil(k) * k).sum())
        .collect()
}

/// The passes each of the `tiles`×`tiles` tiles of a `size` viewport ran, as the numbers the
/// harness writes beside the pass map (named `passes`).
pub fn tile_counts(size: [u32; 2], tiles: u32, tile_size: [u32; 2], passes: &[u32]) -> TileCounts {
    TileCounts {
        name: "passes".into(),
        width: size[0],
        height: size[1],
        tiles: [tiles; 2],
        tile_size,
        counts: passes.to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::passes_per_tile;

    #[test]
    fn each_layer_of_a_tile_is_rounded_up_to_whole_rounds_of_its_longest_stretch() {
        // The top half of a 4×4 view in 2×2 tiles of 2×2 pixels (row-major pixels); the bottom
        // tiles hold no pixel listed.
        let segments = vec![
            vec![3, 9],
            vec![5],
            vec![],
            vec![],
            vec![1, 1, 1],
            vec![],
            vec![],
            vec![],
        ];
        // Left tile: layer 0 longest 5 → 8, layer 1 longest 9 → 16, layer 2 longest 1 → 8;
        // the other tiles have no ray.
        assert_eq!(
            passes_per_tile(&segments, 4, 2, [2, 2], 8),
            vec![32, 0, 0, 0]
        );
        // k = 1 counts the longest stretches exactly.
        assert_eq!(
            passes_per_tile(&segments, 4, 2, [2, 2], 1),
            vec![5 + 9 + 1, 0, 0, 0]
        );
        // One stretch longer in the second layer adds a round.
        let mut more = segments.clone();
        more[0][1] = 17;
        assert_eq!(passes_per_tile(&more, 4, 2, [2, 2], 8), vec![40, 0, 0, 0]);
        // The same walks continued across layers (no restart): the longest whole walk.
        let joined: Vec<Vec<u32>> = segments
            .iter()
            .map(|s| vec![s.iter().sum::<u32>()])
            .collect();
        assert_eq!(passes_per_tile(&joined, 4, 2, [2, 2], 8), vec![16, 0, 0, 0]);
    }
}
