//! What differs between GPUs, forced on the one at hand: the device requested with
//! small storage bindings against the adapter's own (lavapipe 128 MiB, a data-centre GPU about
//! 2 GiB), and with timestamp queries off against the adapter's.
//!
//! With a small `max_storage_buffer_binding_size` the device itself refuses any binding past
//! it (a wgpu validation error, which panics), so a frame that renders at all proves every
//! array over the limit was split: the test checks that each algorithm's largest array is over
//! it, then that the split image equals the whole one.

use datasets::TetMesh;
use harness::algorithms::REGISTRY;
use render_core::gpu::DeviceRequest;
use render_core::{Gpu, Image, Optics, Projection, Renderer, Shading};
use tetbench_tests::{camera, compare, optics, view};

/// The small binding: 256 KiB, the largest fixed-size table an algorithm binds whole
/// (fragment PT's ψ table; the ray caster's 3D table, 32 MiB, is left out below). No real device
/// is this small (WebGPU guarantees 128 MiB); the point is to split the mesh's arrays.
const LOW_BINDING: u64 = 256 << 10;
/// The mesh: every array the algorithms split is over [`LOW_BINDING`] (GATOR's and fragment
/// PT's tets, 16 B/tet; fragment PT's pass-1 records, 32 B/tet; HAVS's faces, 12 B per face,
/// about 2 faces per tet; the ray caster's 144 B/tet), every array they keep whole by design
/// is under it (fragment PT's depths and order, 4 B/tet; the GPU radix sort's keys, 4 B per
/// face; the ray caster's mesh over at most 24 bindings). Checked in the test.
const MESH: &str = "box:24k";
const SIZE: u32 = 32;

fn mesh() -> std::sync::Arc<TetMesh> {
    std::sync::Arc::new(datasets::generate::from_spec(MESH, 1).unwrap())
}

fn open(request: &DeviceRequest) -> Gpu {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", "/tmp");
    }
    Gpu::with_request(request)
        .expect("a wgpu adapter (lavapipe: apt-get install mesa-vulkan-drivers)")
}

/// One frame of `renderer` from a diagonal, and its frame statistics' GPU time.
fn render(
    gpu: &Gpu,
    renderer: &mut dyn Renderer,
    mesh: &std::sync::Arc<TetMesh>,
    optics: &Optics,
) -> (Image, Option<f64>) {
    let cam = camera(mesh, &view([1.0, 1.0, 1.0]), Projection::default(), SIZE);
    let what = format!(
        "{} {} on {}",
        renderer.algorithm(),
        renderer.settings(),
        gpu.adapter.driver_info
    );
    renderer
        .prepare(gpu, mesh, optics)
        .unwrap_or_else(|e| panic!("prepare {what}: {e:#}"));
    let stats = renderer
        .render(gpu, &cam)
        .unwrap_or_else(|e| panic!("render {what}: {e:#}"));
    let image = renderer
        .read_image(gpu)
        .unwrap_or_else(|e| panic!("read {what}: {e:#}"));
    (image, stats.gpu_ms)
}

/// The variants every tetbench algorithm of the registry runs by default (the peers draw
/// through other packages): between them every chunked path (HAVS's CPU and GPU sorts,
/// fragment PT's three orders and two shadings, GATOR's two cell models, the ray caster's
/// default tilings, the splatter's CPU and GPU buckets), and an algorithm added to the
/// registry is checked here without a line of this file. Not HAVS's race-free mode: its
/// fragment lists (16 B per fragment, some 40 fragments per pixel here) must fit one binding,
/// which a binding small enough to split this mesh's faces cannot hold. Nor the ray caster's
/// 3D table (32 MiB, fixed size, bound whole): its 2D-table variants only.
fn variants() -> Vec<Box<dyn Renderer>> {
    REGISTRY
        .iter()
        .filter(|d| !d.is_peer())
        .flat_map(|d| {
            d.default_variants()
                .unwrap_or_else(|e| panic!("{}: {e:#}", d.name))
        })
        .filter(|r| !(r.algorithm() == "raycast" && r.settings().is("table", "3d")))
        .collect()
}

/// Whether two frames of `renderer` on one device must be bit-identical, as its description
/// declares for the way the adapter shades (HAVS's faithful single pass races on a GPU).
fn deterministic(renderer: &dyn Renderer, gpu: &Gpu) -> bool {
    let d = harness::algorithms::description(renderer.algorithm()).unwrap();
    (d.deterministic)(
        &renderer.settings(),
        Shading::of_device_type(&gpu.adapter.device_type),
    )
}

/// Lowest PSNR accepted between the splatter's bricked and unbricked images (every other
/// algorithm must match bit for bit). Bricks are sorted and bucketed apart, so voxels of equal
/// depth from two bricks reach a sheet in another order and their f32 sums round differently;
/// the splatter's own test measured 66 dB between 8 bricks and none (docs/reproduction.md,
/// "Splatting").
const SPLAT_BRICKS_MIN_PSNR_DB: f64 = 60.0;

#[test]
fn small_bindings_give_the_same_image_as_the_adapters_own() {
    let mesh = mesh();
    let optics = optics(&mesh, "low-opacity");
    let n = mesh.num_tets() as u64;
    let high = open(&DeviceRequest::default());
    let low_bytes = LOW_BINDING;
    // Render passes of a few hundred triangles as well: the whole mesh's draws (GATOR's and
    // fragment PT's tets, HAVS's faces) then span dozens of passes, which must blend (or
    // continue the k-buffer) exactly as one pass does.
    let low = open(&DeviceRequest {
        max_storage_binding: Some(low_bytes),
        max_triangles_per_pass: Some(500),
        ..Default::default()
    });
    assert_eq!(low.triangles_per_pass, 500);
    assert_eq!(
        low.max_storage_binding(),
        low_bytes,
        "the device took the limit"
    );
    assert_eq!(low.limits.max_storage_buffer_binding_size, low_bytes);
    assert!(
        high.max_storage_binding() >= 16 * low_bytes,
        "the adapter's own binding ({}) is far above the forced one ({low_bytes})",
        high.max_storage_binding()
    );
    // Every split array is over the small binding (else nothing would be split)…
    let faces = mesh.unique_faces().faces.len() as u64;
    for (what, bytes) in [
        ("GATOR / fragment PT tets", 16 * n),
        ("fragment PT pass-1 records", 32 * n),
        ("HAVS faces", 12 * faces),
        ("ray caster mesh", 144 * n),
    ] {
        assert!(
            bytes > low_bytes,
            "{what}: {bytes} B, binding {low_bytes} B"
        );
    }
    // …and every array kept whole is under it (else the row would fail instead).
    assert!(4 * faces <= low_bytes && 4 * n <= low_bytes && 144 * n <= 24 * low_bytes);

    let mut failures = vec![];
    for (mut whole, mut split) in variants().into_iter().zip(variants()) {
        let (a, _) = render(&high, whole.as_mut(), &mesh, &optics);
        let (b, _) = render(&low, split.as_mut(), &mesh, &optics);
        let name = format!("{} {}", whole.algorithm(), whole.settings());
        let covered = a.pixels.iter().filter(|p| p[3] > 0.0).count();
        assert!(
            covered > (SIZE * SIZE / 4) as usize,
            "{name}: only {covered} pixels drawn"
        );
        if whole.algorithm() == "splat" {
            let e = compare(&b, &a).unwrap();
            eprintln!("{name}: bricked vs whole {:.1} dB", e.psnr_db);
            if e.psnr_db < SPLAT_BRICKS_MIN_PSNR_DB {
                failures.push(format!("{name}: {:.1} dB", e.psnr_db));
            }
        } else if !deterministic(whole.as_ref(), &high) {
            eprintln!("{name}: racy on {}, not compared", high.adapter.name);
        } else if a.pixels != b.pixels {
            let e = compare(&b, &a).unwrap();
            failures.push(format!(
                "{name}: differs (max {:.2e}, {:.1} dB)",
                e.max_abs_error, e.psnr_db
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "split ≠ whole:\n  {}",
        failures.join("\n  ")
    );
}

/// `gpu_ms` is filled exactly when the device has timestamp queries, and the image does not
/// depend on them. With them off every algorithm must still render (no path may assume them).
#[test]
fn gpu_time_appears_exactly_with_timestamp_queries() {
    let mesh = std::sync::Arc::new(datasets::generate::from_spec("box:1k", 1).unwrap());
    let optics = optics(&mesh, "low-opacity");
    let with = open(&DeviceRequest::default());
    let without = open(&DeviceRequest {
        no_timestamps: true,
        ..Default::default()
    });
    assert!(!without.has_timestamps());
    eprintln!(
        "adapter {}: timestamp queries {}",
        with.adapter.name,
        if with.has_timestamps() {
            "present"
        } else {
            "absent"
        }
    );
    for (mut on, mut off) in variants().into_iter().zip(variants()) {
        let name = format!("{} {}", on.algorithm(), on.settings());
        let (a, gpu_on) = render(&with, on.as_mut(), &mesh, &optics);
        let (b, gpu_off) = render(&without, off.as_mut(), &mesh, &optics);
        assert_eq!(gpu_off, None, "{name}: GPU time without timestamp queries");
        if with.has_timestamps() {
            let ms = gpu_on.unwrap_or_else(|| panic!("{name}: no GPU time with timestamps"));
            assert!(ms.is_finite() && ms >= 0.0, "{name}: gpu_ms {ms}");
        } else {
            assert_eq!(gpu_on, None, "{name}");
        }
        if deterministic(on.as_ref(), &with) {
            assert!(
                a.pixels == b.pixels,
                "{name}: the image depends on timestamps"
            );
        }
    }
}

/// HAVS's GPU sort split over storage bindings (a 20 M-tet mesh's ~40 M face keys
/// are 160 MB, over lavapipe's 128 MiB binding). With the binding at 64 KiB (16,384 keys) the
/// mesh's face keys need four bindings; the device refuses any binding past the limit, so a
/// frame proves the key pass and the sort were split, and its image equals the one sorted in
/// a single binding, bit for bit (the split sort's order equals the CPU radix sort's:
/// `render_core::gpu_sort`'s tests).
#[test]
fn havs_gpu_sort_over_several_bindings_gives_the_same_image() {
    let mesh = mesh();
    let optics = optics(&mesh, "low-opacity");
    let faces = mesh.unique_faces().faces.len() as u64;
    let low_bytes: u64 = 64 << 10;
    assert!(
        4 * faces > 3 * low_bytes,
        "{faces} face keys fit {low_bytes}-byte bindings in fewer than four"
    );
    let high = open(&DeviceRequest::default());
    let low = open(&DeviceRequest {
        max_storage_binding: Some(low_bytes),
        ..Default::default()
    });
    assert_eq!(low.max_storage_binding(), low_bytes);
    let gpu_sorted = || {
        havs::DESCRIPTION
            .default_variants()
            .unwrap()
            .into_iter()
            .filter(|r| r.settings().is("sort", "gpu-radix"))
            .collect::<Vec<_>>()
    };
    let mut compared = 0;
    for (mut whole, mut split) in gpu_sorted().into_iter().zip(gpu_sorted()) {
        let name = format!("{} {}", whole.algorithm(), whole.settings());
        let (a, _) = render(&high, whole.as_mut(), &mesh, &optics);
        let (b, _) = render(&low, split.as_mut(), &mesh, &optics);
        if !deterministic(whole.as_ref(), &high) {
            eprintln!("{name}: racy on {}, not compared", high.adapter.name);
            continue;
        }
        assert!(
            a.pixels == b.pixels,
            "{name}: the split sort's image differs"
        );
        compared += 1;
    }
    assert!(
        compared > 0 || high.adapter.device_type != "Cpu",
        "no GPU-sorted HAVS variant compared"
    );
}
