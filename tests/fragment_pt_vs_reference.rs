//! Fragment PT (Marroquim et al. 2006) against the exact reference: both shading modes (average
//! scalar with the exponential table; partial pre-integration with the ψ table) with the exact
//! MPVONC order and the paper's orders, on a generated grid (always runs) and on SPX (when the
//! data directory is present), at 128² with the low-opacity transfer function.
//!
//! PSNR as the harness reports it: RGB of the premultiplied image over black, clamped to
//! [0, 1], every pixel, peak 1.

use datasets::TetMesh;
use fragment_pt::{FragmentPt, FragmentPtSettings, Shading, SortMode};
use render_core::{Camera, Gpu, Image, Optics, Projection, Renderer};
use tetbench_tests::{assert_finite, camera, gpu, grid_mesh, optics, spx, view, Scene};

fn render(
    gpu: &Gpu,
    mesh: &std::sync::Arc<TetMesh>,
    optics: &Optics,
    shading: Shading,
    sort: SortMode,
    camera: &Camera,
) -> Image {
    let mut r = FragmentPt::new(FragmentPtSettings {
        shading,
        sort,
        slabs: None,
    });
    let prepared = r.prepare(gpu, mesh, optics).unwrap();
    assert_eq!(prepared.tets, mesh.num_tets() as u64);
    // The model is a tet-index array and a vertex array only (the paper's ≈ 20 B/tet).
    let model = r.model_bytes().unwrap();
    assert_eq!(
        model,
        16 * mesh.num_tets() as u64 + 16 * mesh.num_points() as u64
    );
    let stats = r.render(gpu, camera).unwrap();
    assert!(stats.total_ms > 0.0);
    let img = r.read_image(gpu).unwrap();
    assert_finite(&img, "fragment-pt");
    img
}

#[test]
fn fragment_pt_on_a_grid_is_within_bounds_of_the_reference() {
    let gpu = gpu();
    let mesh = grid_mesh();
    let optics = optics(&mesh, "low-opacity");
    let scene = Scene::new(
        &mesh,
        &optics,
        camera(&mesh, &view([1.0, 1.0, 1.0]), Projection::default(), 128),
    );
    let mut got = vec![];
    for (shading, sort) in [
        (Shading::Psi, SortMode::Mpvonc),
        (Shading::Average, SortMode::Mpvonc),
        (Shading::Psi, SortMode::Merge),
        (Shading::Psi, SortMode::Gpu),
        (Shading::Psi, SortMode::Bucket),
    ] {
        let p = scene.psnr(&render(&gpu, &mesh, &optics, shading, sort, &scene.camera));
        eprintln!(
            "grid (6,655 tets, 128², +x+y+z): shading={} sort={}: {p:.2} dB",
            shading.name(),
            sort.name()
        );
        got.push(p);
    }
    // Measured on lavapipe: psi 69.5 dB and average 73.1 dB with MPVONC; psi 69.5 (merge),
    // 69.5 (gpu), 69.4 (bucket). Bounds 3 dB below:
    // empirical bound (no a-priori error bound for this approximation is derived here); safe
    // because the rendering is deterministic on an adapter and f32 rounding differences between
    // drivers move the RMSE by far less than the 3 dB (×1.41 RMSE) margin, while the defects
    // the test exists for (a wrong order, classification or table coordinate, missing tets)
    // cost tens of dB.
    let [psi_mpvonc, avg_mpvonc, psi_merge, psi_gpu, psi_bucket] = got[..] else {
        unreachable!()
    };
    assert!(psi_mpvonc > 66.5, "psi + MPVONC: {psi_mpvonc:.2} dB");
    assert!(avg_mpvonc > 70.0, "average + MPVONC: {avg_mpvonc:.2} dB");
    assert!(
        psi_merge > 66.5 && psi_gpu > 66.5 && psi_bucket > 66.0,
        "{got:?}"
    );
}

#[test]
fn fragment_pt_on_spx_is_within_bounds_of_the_reference() {
    let Some(mesh) = spx() else {
        return;
    };
    let gpu = gpu();
    let optics = optics(&mesh, "low-opacity");
    let mut got = vec![];
    for vp in [view([1.0, 1.0, 1.0]), view([0.0, -1.0, 0.0])] {
        let scene = Scene::new(
            &mesh,
            &optics,
            camera(&mesh, &vp, Projection::default(), 128),
        );
        for shading in [Shading::Psi, Shading::Average] {
            let p = scene.psnr(&render(
                &gpu,
                &mesh,
                &optics,
                shading,
                SortMode::Mpvonc,
                &scene.camera,
            ));
            eprintln!(
                "spx (12,936 tets, 128², {}): shading={} sort=mpvonc: {p:.2} dB",
                vp.name,
                shading.name()
            );
            got.push(p);
        }
    }
    // Measured on lavapipe: psi 74.9 / 74.3 dB, average 76.6 / 75.8 dB (+x+y+z / -y).
    // Bounds 3 dB below:
    // empirical bound (no a-priori error bound for this approximation is derived here); safe
    // because the rendering is deterministic on an adapter and f32 rounding differences between
    // drivers move the RMSE by far less than the 3 dB (×1.41 RMSE) margin, while the defects the
    // test exists for (a wrong order, classification or table coordinate, missing tets) cost tens
    // of dB.
    assert!(
        got[0] > 71.5 && got[2] > 71.0,
        "psi + MPVONC on spx: {got:?}"
    );
    assert!(
        got[1] > 73.0 && got[3] > 72.5,
        "average + MPVONC on spx: {got:?}"
    );
}
