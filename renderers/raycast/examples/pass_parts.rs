//! Table 4's passes and their parts from the CPU twin, with early ray termination off (so that
//! the walks do not depend on the transfer function): per data set, over the 14 viewpoints at
//! 512², the longest walk continued across layers, the passes spent per layer as the paper
//! does at k = 1 and k = 8 on one tile, and the busiest of 6×6 tiles at k = 8.
//!
//! `cargo run -p raycast --example pass_parts -- spx1 bluntfin f117` (data sets from the
//! registry: `TETBENCH_DATA` or `../shared/datasets`).

use raycast::{passmap, step, Mode, Raycast, RaycastSettings, TableKind};
use rayon::prelude::*;
use render_core::{fixed_viewpoints, Camera, Gpu, Optics, Projection, Renderer, TransferFunction};

fn main() -> anyhow::Result<()> {
    let gpu = Gpu::new()?;
    let registry = datasets::registry::Registry::new(None);
    let size = 512;
    for name in std::env::args().skip(1) {
        let data = registry.resolve(&name, &Default::default())?;
        let mesh = std::sync::Arc::new(data.mesh);
        let optics = Optics::for_mesh(
            TransferFunction::preset("low-opacity").expect("a preset"),
            &mesh,
        );
        let mut r = Raycast::new(RaycastSettings {
            tiles: 1,
            table: TableKind::TwoD,
            mode: Mode::Loop,
            early_termination: false,
            max_layers: 32,
            k: raycast::COUNT_EVERY,
            unscaled: false,
        });
        r.prepare(&gpu, &mesh, &optics)?;
        let layout = r.layout(&mesh, &optics)?;
        println!("{name}: view, layers, walk, k1, k8, busiest 6x6 k8, pixels off the GPU");
        for (v, vp) in fixed_viewpoints().iter().enumerate() {
            let camera = Camera::fit(&mesh.bounds(), vp, Projection::default(), size, size);
            r.render(&gpu, &camera)?;
            let d = r.pass_data(&gpu)?;
            let segments: Vec<(u32, Vec<u32>)> = (0..d.width * d.height)
                .into_par_iter()
                .map(|i| {
                    let entries: Vec<_> = d.layers.iter().map(|l| l[i as usize]).collect();
                    let (x, y) = (i % d.width, i / d.width);
                    let (o, dir) = d.ray_frame.ray(x as f32 + 0.5, y as f32 + 0.5);
                    let (w, s) =
                        step::walk_segments(&layout, &entries, o, dir, d.bias, d.max_steps);
                    (w.steps, s)
                })
                .collect();
            let off = (segments.iter().zip(&d.steps))
                .filter(|((s, _), g)| s != *g)
                .count();
            let segs: Vec<Vec<u32>> = segments.into_iter().map(|(_, s)| s).collect();
            let walk = d.steps.iter().copied().max().unwrap_or(0);
            let one = |k| passmap::passes_per_tile(&segs, d.width, 1, [d.width, d.height], k)[0];
            let tile = [d.width.div_ceil(6), d.height.div_ceil(6)];
            let tiled = passmap::passes_per_tile(&segs, d.width, 6, tile, 8);
            println!(
                "{name} v{v}: {} {walk} {} {} {} {off}",
                d.layers_used,
                one(1),
                one(8),
                tiled.iter().max().unwrap_or(&0)
            );
        }
    }
    Ok(())
}
