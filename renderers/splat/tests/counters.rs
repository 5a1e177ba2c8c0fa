//! The splatter's work counters against the GPU's own counts (issue 23, item 6):
//! `splat_fragments` (derived on the CPU, `coverage.rs`) against the fragments the rasteriser
//! produced, counted by the early-splat-elimination atomic with every fragment dropped;
//! `splats` against the bucket table's ranges; the composite's fragments and the triangles.

use datasets::TetMesh;
use render_core::{Camera, Gpu, Optics, Projection, Renderer, TransferFunction, Viewpoint};
use splat::{Buckets, GpuSort, Splat, SplatSettings};

fn gpu() -> Gpu {
    Gpu::new().expect("a wgpu adapter (lavapipe: apt-get install mesa-vulkan-drivers)")
}

fn counter(stats: &render_core::FrameStats, name: &str) -> f64 {
    stats
        .counters
        .iter()
        .find(|(k, _)| k == name)
        .map(|(_, v)| *v)
        .unwrap_or_else(|| panic!("no counter {name}"))
}

fn camera(mesh: &TetMesh, vp: &str, dir: [f64; 3], projection: Projection) -> Camera {
    Camera::fit(&mesh.bounds(), &Viewpoint::new(vp, dir), projection, 64, 48)
}

#[test]
fn splat_fragments_bound_the_rasterisers_count_and_splats_match_the_buckets() {
    let gpu = gpu();
    let mesh = datasets::gen_volume::from_volume_spec("vol:20x18x16").unwrap();
    let optics = Optics::for_mesh(TransferFunction::preset("low-opacity").unwrap(), &mesh);
    for (vp, dir, proj) in [
        ("+x+y+z", [1.0, 1.0, 1.0], Projection::default()),
        ("+x", [1.0, 0.0, 0.0], Projection::Orthographic),
    ] {
        let cam = camera(&mesh, vp, dir, proj);
        for (buckets, radius) in [
            (Buckets::Cpu, 2.0),
            (Buckets::Gpu, 2.0),
            (Buckets::Cpu, 1.5),
        ] {
            let settings = SplatSettings {
                buckets,
                sort: GpuSort::Bitonic,
                radius,
                ..Default::default()
            };
            let what = format!("{vp} {buckets:?} radius {radius}");
            let mut r = Splat::new(settings).counting_every_fragment();
            r.prepare(&gpu, &mesh, &optics).unwrap();
            let stats = r.render(&gpu, &cam).unwrap();
            let cover = r.fragment_count(&cam).unwrap();
            let rasterised = counter(&stats, "ese_dropped_fragments") as u64;
            assert!(cover.fragments > 10_000, "{what}: {cover:?}");
            assert!(
                (cover.at_least..=cover.at_most).contains(&rasterised),
                "{what}: the GPU rasterised {rasterised} splat fragments, the twin {cover:?}"
            );
            assert_eq!(counter(&stats, "splat_fragments"), cover.fragments as f64);
            assert_eq!(counter(&stats, "splats"), cover.splats as f64, "{what}");
            let slabs = counter(&stats, "slabs");
            assert_eq!(counter(&stats, "fragments"), slabs * 64.0 * 48.0);
            assert_eq!(
                counter(&stats, "triangles"),
                2.0 * cover.splats as f64 + slabs
            );
            let voxels = counter(&stats, "effective_voxels");
            let sorted = match buckets {
                Buckets::Cpu => "cpu_sort_keys",
                Buckets::Gpu => "gpu_sort_keys",
            };
            assert_eq!(counter(&stats, sorted), voxels);
        }
    }
}
