//! Times the exact reference on named data sets at a given resolution over the 14 fixed
//! viewpoints: `cargo run --release -p reference --example reference_timing -- spx bluntfin 512`.

use datasets::registry::Registry;
use datasets::LoadOptions;
use render_core::{fixed_viewpoints, Camera, Optics, Projection, TransferFunction};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let res: u32 = args.iter().find_map(|a| a.parse().ok()).unwrap_or(512);
    let names: Vec<&String> = args.iter().filter(|a| a.parse::<u32>().is_err()).collect();
    let tf_name = std::env::var("TF").unwrap_or_else(|_| "low-opacity".into());
    let registry = Registry::new(None);
    for name in names {
        let ds = registry.resolve(name, &LoadOptions::default())?;
        let mesh = ds.mesh;
        let optics = Optics::for_mesh(TransferFunction::load(&tf_name)?, &mesh);
        let t0 = std::time::Instant::now();
        let prep = reference::Prepared::new(&mesh);
        let prep_ms = t0.elapsed().as_secs_f64() * 1e3;
        let mut times = Vec::new();
        let mut total = reference::RenderStats::default();
        for vp in fixed_viewpoints() {
            let cam = Camera::fit(&mesh.bounds(), &vp, Projection::default(), res, res);
            let t = std::time::Instant::now();
            let (_, st) = prep.render(&optics, &cam);
            times.push(t.elapsed().as_secs_f64());
            total.segments += st.segments;
            total.relocations += st.relocations;
            total.reentries += st.reentries;
        }
        times.sort_by(f64::total_cmp);
        println!(
            "{name}: {} tets, {res}x{res}, tf {tf_name}, {} threads: prepare {prep_ms:.0} ms; render median {:.2} s (min {:.2}, max {:.2}) over 14 views; {:.1} M segments/view, {} relocations, {} re-entries in all",
            mesh.num_tets(),
            rayon::current_num_threads(),
            times[7],
            times[0],
            times[13],
            total.segments as f64 / 14e6,
            total.relocations,
            total.reentries
        );
    }
    Ok(())
}
