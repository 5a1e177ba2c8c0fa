//! Times tetbench's exact reference (the CPU ray walk, `reference::Prepared::render`) per view,
//! the ray caster that `vtk-raycast` is compared with in docs/peers.md's performance section:
//!
//! `cargo run --release -p vtk-peer --example reference_speed -- spx,bluntfin 512 14`
//!
//! Arguments: data sets (registry names or generator specs), square resolution, viewpoints
//! (`14` or names as `tetbench run --viewpoints` takes). Prints per data set the median ms per
//! view and tets/s over the views; the per-mesh preparation (planes, boundary bins) is done once
//! and not timed, as a renderer's `prepare`.

use std::time::Instant;

use render_core::{fixed_viewpoints, Camera, Optics, Projection, TransferFunction, Viewpoint};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let datasets = args.first().map(String::as_str).unwrap_or("spx");
    let size: u32 = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(512);
    let views: Vec<Viewpoint> = match args.get(2).map(String::as_str) {
        None | Some("14") => fixed_viewpoints(),
        Some(names) => fixed_viewpoints()
            .into_iter()
            .filter(|v| names.split(',').any(|n| n == v.name))
            .collect(),
    };
    let registry = datasets::registry::Registry::new(None);
    let tf = TransferFunction::preset("low-opacity").expect("preset");
    for name in datasets.split(',') {
        let mesh = registry
            .resolve(name, &Default::default())
            .map_err(|e| anyhow::anyhow!("{e}"))?
            .mesh;
        let optics = Optics::for_mesh(tf.clone(), &mesh);
        let prepared = reference::Prepared::new(&mesh);
        let mut ms: Vec<f64> = views
            .iter()
            .map(|vp| {
                let camera = Camera::fit(&mesh.bounds(), vp, Projection::default(), size, size);
                let t0 = Instant::now();
                let _ = prepared.render(&optics, &camera);
                t0.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        ms.sort_by(f64::total_cmp);
        let median = ms[ms.len() / 2];
        println!(
            "reference on {name} ({} tets, {size}², {} views, {} threads): median {median:.1} ms \
             per view, {:.3} M tets/s (min {:.1} ms, max {:.1} ms)",
            mesh.num_tets(),
            views.len(),
            rayon::current_num_threads(),
            mesh.num_tets() as f64 / median * 1e-3,
            ms[0],
            ms[ms.len() - 1]
        );
    }
    Ok(())
}
