//! The splatter's work counters against the GPU's own counts:
//! `splat_fragments` (derived on the CPU, `coverage.rs`) against the fragments the compute
//! pass visited, counted by the early-splat-elimination atomic with every fragment dropped;
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
fn splat_fragments_bound_the_gpus_count_and_splats_match_the_buckets() {
    let gpu = gpu();
    let mesh = std::sync::Arc::new(datasets::gen_volume::from_volume_spec("vol:20x18x16").unwrap());
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
                "{what}: the GPU visited {rasterised} splat fragments, the twin {cover:?}"
            );
            assert_eq!(counter(&stats, "splat_fragments"), cover.fragments as f64);
            assert_eq!(counter(&stats, "splats"), cover.splats as f64, "{what}");
            let slabs = counter(&stats, "slabs");
            // The composite covers the sheet's rectangle: the volume with its kernels.
            let [x0, y0, x1, y1] = r.composite_rect(&cam).unwrap();
            assert!(
                x0 < x1 && y0 < y1 && (x1 - x0) * (y1 - y0) <= 64 * 48,
                "{what}"
            );
            assert_eq!(
                counter(&stats, "fragments"),
                slabs * ((x1 - x0) * (y1 - y0)) as f64
            );
            assert_eq!(counter(&stats, "triangles"), slabs);
            let voxels = counter(&stats, "effective_voxels");
            let sorted = match buckets {
                Buckets::Cpu => "cpu_sort_keys",
                Buckets::Gpu => "gpu_sort_keys",
            };
            assert_eq!(counter(&stats, sorted), voxels);
        }
    }
}

/// The composite is scissored to `composite_rect`, and it also zeroes the sheet: a footprint
/// pixel outside the rectangle would stay in the sheet for every later slab. Checked from a
/// distance (the volume a small part of the viewport), where the rectangle is a real cut.
#[test]
fn every_footprint_lies_inside_the_composite_rectangle() {
    let gpu = gpu();
    let mesh = std::sync::Arc::new(datasets::gen_volume::from_volume_spec("vol:20x18x16").unwrap());
    let optics = Optics::for_mesh(TransferFunction::preset("low-opacity").unwrap(), &mesh);
    let mut r = Splat::new(SplatSettings::default());
    r.prepare(&gpu, &mesh, &optics).unwrap();
    for (vp, dir, proj) in [
        ("+x+y+z", [1.0, 1.0, 1.0], Projection::default()),
        ("+x", [1.0, 0.0, 0.0], Projection::Orthographic),
    ] {
        let fit = camera(&mesh, vp, dir, proj);
        // Fitted to a box three times the volume's: the volume is a ninth of the view.
        let b = mesh.bounds();
        let c = b.center();
        let wider = datasets::Aabb {
            min: std::array::from_fn(|a| c[a] - 1.5 * (b.max[a] - b.min[a])),
            max: std::array::from_fn(|a| c[a] + 1.5 * (b.max[a] - b.min[a])),
        };
        let far = Camera::fit(&wider, &Viewpoint::new(vp, dir), proj, 256, 192);
        for cam in [fit, far] {
            let rect = r.composite_rect(&cam).unwrap();
            let [x0, y0, x1, y1] = rect;
            let what = format!("{vp} at {}x{}: {rect:?}", cam.width, cam.height);
            assert_eq!(r.centres_outside(&cam, rect).unwrap(), 0, "{what}");
            if cam.width == 256 {
                assert!((x1 - x0) * (y1 - y0) < 256 * 192 / 2, "{what}");
                // The check can fail: the rectangle's middle half leaves pixels out.
                let (qx, qy) = ((x1 - x0) / 4, (y1 - y0) / 4);
                let narrower = [x0 + qx, y0 + qy, x1 - qx, y1 - qy];
                assert!(r.centres_outside(&cam, narrower).unwrap() > 0, "{what}");
            }
        }
    }
}
