//! Every algorithm in the registry against the exact reference on one check scene, with the
//! tolerance its description declares (`AlgorithmDescription::tolerance`): a smooth analytic
//! field on a structured grid (6,655 tets), 128², the low-opacity transfer function, the
//! `+x+y+z` view. Each default variant of each of tetbench's algorithms renders once; the
//! test also checks that every frame reports the work counters its description names (the
//! roofline reads them). The peers run in `vtk_vs_reference.rs`, which needs VTK.
//!
//! Per-algorithm tests (`gator_vs_reference.rs`, `havs_vs_reference.rs`, …) keep only what
//! is particular to an algorithm (linear vs constant cells, k-buffer overflow, orders).

use harness::algorithms::REGISTRY;
use render_core::Projection;
use tetbench_tests::{assert_finite, camera, gpu, grid_mesh, optics, view, Scene};

#[test]
fn every_algorithm_is_within_its_declared_tolerance_of_the_reference() {
    let gpu = gpu();
    let mesh = std::sync::Arc::new(grid_mesh());
    let optics = optics(&mesh, "low-opacity");
    let scene = Scene::new(
        &mesh,
        &optics,
        camera(&mesh, &view([1.0, 1.0, 1.0]), Projection::default(), 128),
    );
    let mut failures = vec![];
    for d in REGISTRY.iter().filter(|d| !d.is_peer()) {
        for settings in (d.default_grid)() {
            let mut r = (d.build)(&settings).unwrap();
            let prepared = r.prepare(&gpu, &mesh, &optics).unwrap();
            assert_eq!(
                prepared.tets,
                mesh.num_tets() as u64,
                "{} {settings}",
                d.name
            );
            let stats = r.render(&gpu, &scene.camera).unwrap();
            let img = r.read_image(&gpu).unwrap();
            assert_finite(&img, d.name);
            let p = scene.psnr(&img);
            let t = (d.tolerance)(&settings);
            // The check can fail: the same image upside down is far outside every tolerance.
            let mut flipped = img.clone();
            let w = img.width as usize;
            for (y, row) in flipped.pixels.chunks_mut(w).enumerate() {
                let src = img.height as usize - 1 - y;
                row.copy_from_slice(&img.pixels[src * w..(src + 1) * w]);
            }
            assert!(
                scene.psnr(&flipped) < t.min_psnr_db,
                "{} {settings}: a flipped image passes its tolerance",
                d.name
            );
            eprintln!(
                "{} {settings}: {p:.2} dB (declared minimum {:.1} dB: {})",
                d.name, t.min_psnr_db, t.why
            );
            if p.is_nan() || p < t.min_psnr_db {
                failures.push(format!(
                    "{} {settings}: {p:.2} dB < {:.1} dB",
                    d.name, t.min_psnr_db
                ));
            }
            for c in d.counters {
                let reported = stats.counters.iter().any(|(name, _)| name == c);
                // A variant reports the sort counter of the sort it runs, not the other.
                let other_sort = c.ends_with("sort_keys")
                    && stats.counters.iter().any(|(n, _)| n.ends_with("sort_keys"));
                if !reported && !other_sort {
                    failures.push(format!("{} {settings}: no counter {c}", d.name));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
