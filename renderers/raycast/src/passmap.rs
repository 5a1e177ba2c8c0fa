//! The pass-count map (the paper's Fig. 5): every tile filled with a colour for the number of
//! ray-casting passes it ran, brighter where a ray entered the mesh, with dark tile borders.

use render_core::Image;

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
