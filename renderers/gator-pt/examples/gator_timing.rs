//! Times GATOR on data sets at the 14 fixed viewpoints and prints tets/s, CPU/GPU/total ms and
//! bytes/tet per variant: a quick check outside the harness (`tetbench run` is the real one).
//!
//! `cargo run --release -p gator-pt --example gator_timing -- FILE [FILE…] [--size 512] [--frames 5]
//! [--sort radix|bucket|merge|mpvonc] [--psnr N]` (`--psnr N`: PSNR against the exact reference
//! at the first N viewpoints, RGB over black as the harness reports it).

use gator_pt::{CellModel, GatorPt, VisibilityOrder};
use render_core::{fixed_viewpoints, Camera, Gpu, Optics, Projection, Renderer, TransferFunction};

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn main() -> anyhow::Result<()> {
    let mut files = Vec::new();
    let mut size = 512u32;
    let mut frames = 5usize;
    let mut order = VisibilityOrder::default();
    let mut psnr_views = 0usize;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--size" => {
                size = args
                    .next()
                    .ok_or_else(|| anyhow::anyhow!("--size needs a value"))?
                    .parse()?
            }
            "--frames" => {
                frames = args
                    .next()
                    .ok_or_else(|| anyhow::anyhow!("--frames needs a value"))?
                    .parse()?
            }
            "--sort" => {
                order = args
                    .next()
                    .ok_or_else(|| anyhow::anyhow!("--sort needs a value"))?
                    .parse()?
            }
            "--psnr" => {
                psnr_views = args
                    .next()
                    .ok_or_else(|| anyhow::anyhow!("--psnr needs a value"))?
                    .parse()?
            }
            _ => files.push(a),
        }
    }
    let gpu = Gpu::new()?;
    println!(
        "adapter: {} ({}, {})",
        gpu.adapter.name, gpu.adapter.backend, gpu.adapter.driver
    );
    for file in files {
        let mesh = std::sync::Arc::new(
            datasets::load::load(std::path::Path::new(&file), &Default::default())?.mesh,
        );
        let optics = Optics::for_mesh(
            TransferFunction::preset("low-opacity").expect("preset"),
            &mesh,
        );
        for cells in [CellModel::Constant, CellModel::Linear] {
            let mut r = GatorPt::new(cells, order);
            let prepared = r.prepare(&gpu, &mesh, &optics)?;
            let (mut total, mut cpu, mut gpu_ms) = (Vec::new(), Vec::new(), Vec::new());
            for vp in fixed_viewpoints() {
                let cam = Camera::fit(&mesh.bounds(), &vp, Projection::default(), size, size);
                for f in 0..frames + 2 {
                    let s = r.render(&gpu, &cam)?;
                    if f >= 2 {
                        total.push(s.total_ms);
                        cpu.push(s.cpu_ms);
                        gpu_ms.push(s.gpu_ms.unwrap_or(f64::NAN));
                    }
                }
            }
            let mut psnrs = Vec::new();
            for vp in fixed_viewpoints().iter().take(psnr_views) {
                let cam = Camera::fit(&mesh.bounds(), vp, Projection::default(), size, size);
                r.render(&gpu, &cam)?;
                let img = r.read_image(&gpu)?;
                let reference = reference::render(&mesh, &optics, &cam);
                let mut se = 0.0;
                for (p, q) in img.pixels.iter().zip(&reference.pixels) {
                    for c in 0..3 {
                        let d = p[c].clamp(0.0, 1.0) as f64 - q[c].clamp(0.0, 1.0) as f64;
                        se += d * d;
                    }
                }
                psnrs.push(format!(
                    "{} {:.2} dB",
                    vp.name,
                    -10.0 * (se / (img.pixels.len() * 3) as f64).log10()
                ));
            }
            if !psnrs.is_empty() {
                println!("  PSNR vs reference: {}", psnrs.join(", "));
            }
            let t = median(&mut total);
            println!(
                "{} ({} tets) {}² {:?} sort={}: total {:.2} ms (cpu {:.2}, gpu {:.2}), {:.2} M tets/s, {} persistent bytes = {:.1} B/tet",
                mesh.name,
                mesh.num_tets(),
                size,
                cells,
                order,
                t,
                median(&mut cpu),
                median(&mut gpu_ms),
                mesh.num_tets() as f64 / t * 1e-3,
                prepared.persistent_bytes,
                prepared.persistent_bytes as f64 / mesh.num_tets() as f64
            );
        }
    }
    Ok(())
}
