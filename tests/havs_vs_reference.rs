//! HAVS (Callahan et al. 2005) against the exact reference: k = 6 on SPX, the two-tag scheme
//! against the single tag the paper shipped on a non-convex mesh, the race-free mode against
//! its CPU model, and the GPU sort against the CPU sort. Images are small (≤ 128²) so the suite
//! stays fast on lavapipe.

use datasets::TetMesh;
use havs::abuffer::model_image;
use havs::{tagged_geometry, Havs, HavsSettings, Mode, SortMode, TagScheme};
use render_core::preintegration::Table3d;
use render_core::{
    fixed_viewpoints, Camera, Gpu, Image, Optics, Projection, Renderer, TransferFunction,
};

/// PSNR (dB) over the premultiplied linear RGBA of two images, peak 1.
fn psnr(a: &Image, b: &Image) -> f64 {
    let mut se = 0.0;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..4 {
            let d = p[c].clamp(0.0, 1.0) as f64 - q[c].clamp(0.0, 1.0) as f64;
            se += d * d;
        }
    }
    let mse = se / (a.pixels.len() * 4) as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        -10.0 * mse.log10()
    }
}

fn gpu() -> Gpu {
    std::env::set_var(
        "XDG_RUNTIME_DIR",
        std::env::var("XDG_RUNTIME_DIR").unwrap_or_else(|_| "/tmp".into()),
    );
    Gpu::new().expect("a wgpu adapter (lavapipe: apt-get install mesa-vulkan-drivers)")
}

fn render(
    gpu: &Gpu,
    mesh: &TetMesh,
    optics: &Optics,
    settings: HavsSettings,
    camera: &Camera,
) -> (Image, Vec<(String, f64)>) {
    let mut r = Havs::new(settings);
    r.prepare(gpu, mesh, optics).unwrap();
    let stats = r.render(gpu, camera).unwrap();
    assert!(stats.total_ms > 0.0);
    (r.read_image(gpu).unwrap(), stats.counters)
}

fn counter(c: &[(String, f64)], name: &str) -> f64 {
    c.iter()
        .find(|(n, _)| n == name)
        .map(|x| x.1)
        .unwrap_or(f64::NAN)
}

/// A comb: a base bar with teeth one cell wide and one cell thick, cut from a structured grid.
/// Rays from a diagonal leave and re-enter the mesh between teeth, and cross the corner tets
/// of a tooth entering and leaving through two boundary faces of the same tet — the case the
/// single tag gets wrong (HAVS §4).
fn comb_mesh() -> TetMesh {
    let dims = [17usize, 13, 3];
    let mut points = Vec::new();
    let mut scalars = Vec::new();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let p = [i as f32 * 0.5, j as f32 * 0.5, k as f32 * 0.5];
                points.push(p);
                scalars.push((p[0] * 0.7 + p[1] * 0.5 + p[2]).sin() + p[1] * 0.2);
            }
        }
    }
    let mut tets = Vec::new();
    for k in 0..dims[2] - 1 {
        for j in 0..dims[1] - 1 {
            for i in 0..dims[0] - 1 {
                let base = j == 0;
                let tooth = j >= 1 && i % 2 == 0 && k == 0;
                if base || tooth {
                    tets.extend_from_slice(&datasets::volume::hex_cell_tets(dims, i, j, k));
                }
            }
        }
    }
    TetMesh::new("comb", points, scalars, "f", tets).unwrap()
}

#[test]
fn two_tags_beat_the_single_tag_on_a_non_convex_mesh() {
    let gpu = gpu();
    let mesh = comb_mesh();
    assert!(!mesh.is_convex());
    let optics = Optics::for_mesh(TransferFunction::preset("high-opacity").unwrap(), &mesh);
    let vp = &fixed_viewpoints()[6];
    let camera = Camera::fit(&mesh.bounds(), vp, Projection::default(), 96, 96);
    let reference = reference::render(&mesh, &optics, &camera);
    let mut psnrs = vec![];
    for tags in [TagScheme::Two, TagScheme::Single] {
        let s = HavsSettings {
            k: 6,
            tags,
            table_scalar: 64,
            table_length: 64,
            ..Default::default()
        };
        let (img, _) = render(&gpu, &mesh, &optics, s, &camera);
        psnrs.push(psnr(&img, &reference));
    }
    eprintln!(
        "comb ({} tets) vs reference: two tags {:.2} dB, single tag {:.2} dB",
        mesh.num_tets(),
        psnrs[0],
        psnrs[1]
    );
    // Measured on lavapipe: two tags 82 dB, single tag 25 dB.
    assert!(
        psnrs[0] > 60.0,
        "two-tag HAVS is {:.2} dB from the reference",
        psnrs[0]
    );
    assert!(
        psnrs[0] > psnrs[1] + 10.0,
        "two tags {:.2} dB, single {:.2} dB",
        psnrs[0],
        psnrs[1]
    );
}

#[test]
fn race_free_mode_matches_its_cpu_model_and_gpu_sort_matches_cpu_sort() {
    let gpu = gpu();
    let mesh = comb_mesh();
    let optics = Optics::for_mesh(TransferFunction::preset("low-opacity").unwrap(), &mesh);
    let camera = Camera::fit(
        &mesh.bounds(),
        &fixed_viewpoints()[9],
        Projection::default(),
        64,
        64,
    );
    let base = HavsSettings {
        k: 2,
        table_scalar: 64,
        table_length: 64,
        ..Default::default()
    };
    let (race_free, c) = render(
        &gpu,
        &mesh,
        &optics,
        HavsSettings {
            mode: Mode::RaceFree,
            ..base
        },
        &camera,
    );
    let table = Table3d::build(&optics, 64, 64, mesh.quality().max_edge);
    let (model, model_errors) = model_image(
        &tagged_geometry(&mesh, &optics),
        &camera,
        &table,
        2,
        TagScheme::Two,
        true,
    );
    let p = psnr(&race_free, &model);
    eprintln!(
        "race-free GPU vs CPU model: {p:.2} dB; out-of-order pops GPU {} CPU {model_errors}; fragments {}",
        counter(&c, "kbuffer_out_of_order"),
        counter(&c, "fragments")
    );
    assert!(
        p > 60.0,
        "race-free GPU and its CPU model differ: {p:.2} dB"
    );
    let (cpu_sorted, _) = render(&gpu, &mesh, &optics, base, &camera);
    let (gpu_sorted, _) = render(
        &gpu,
        &mesh,
        &optics,
        HavsSettings {
            sort: SortMode::GpuRadix,
            ..base
        },
        &camera,
    );
    let p = psnr(&cpu_sorted, &gpu_sorted);
    eprintln!("GPU sort vs CPU sort: {p:.2} dB");
    assert!(p > 45.0, "GPU-sorted and CPU-sorted HAVS differ: {p:.2} dB");
}

#[test]
fn havs_k6_on_spx_is_close_to_the_reference() {
    let Some(dir) = tetbench_tests::data_dir() else {
        return;
    };
    let mesh = datasets::load::load(&dir.join("spx.vtk"), &Default::default())
        .unwrap()
        .mesh;
    let gpu = gpu();
    let optics = Optics::for_mesh(TransferFunction::preset("low-opacity").unwrap(), &mesh);
    let camera = Camera::fit(
        &mesh.bounds(),
        &fixed_viewpoints()[6],
        Projection::default(),
        128,
        128,
    );
    let reference = reference::render(&mesh, &optics, &camera);
    for mode in [Mode::FragmentRace, Mode::RaceFree] {
        for k in [2, 6] {
            let s = HavsSettings {
                k,
                mode,
                ..Default::default()
            };
            let (img, c) = render(&gpu, &mesh, &optics, s, &camera);
            let p = psnr(&img, &reference);
            eprintln!(
                "spx k={k} {}: {p:.2} dB vs reference, {} fragments, {} out-of-order pops",
                mode.name(),
                counter(&c, "fragments"),
                counter(&c, "kbuffer_out_of_order")
            );
            // Measured on lavapipe: 84 dB at k = 6 (no out-of-order pops), 75 dB at k = 2.
            let bound = if k == 6 { 70.0 } else { 55.0 };
            assert!(
                p > bound,
                "HAVS k={k} {} on spx is {p:.2} dB from the reference",
                mode.name()
            );
        }
    }
}

/// Issue 15: `onion:10k` (nested sliver shells, every tet a sliver) is built to break a small
/// k-buffer. The exact A-buffer analysis finds the k it needs; the k-buffer's CPU model with
/// that k is out of order nowhere and close to the reference, while k = 2 is out of order
/// somewhere and further from it. (CPU only: the model is the twin of the race-free GPU mode.)
#[test]
fn the_sliver_onion_needs_more_than_k_2() {
    let mesh = datasets::generate::from_spec("onion:10k", 1).unwrap();
    assert_eq!(mesh.quality().slivers, mesh.num_tets());
    let optics = Optics::for_mesh(TransferFunction::preset("low-opacity").unwrap(), &mesh);
    let vp = &fixed_viewpoints()[6];
    let camera = Camera::fit(&mesh.bounds(), vp, Projection::default(), 64, 64);
    let geometry = tagged_geometry(&mesh, &optics);
    let stats = havs::abuffer::kbuffer_stats(&geometry, &camera);
    eprintln!(
        "onion:10k at 64²: max k {}, pixels needing k > 2: {}, k > 6: {} of {}",
        stats.max_k, stats.pixels_k_gt2, stats.pixels_k_gt6, stats.covered_pixels
    );
    // Measured: max k 3, 2,204 of 2,226 covered pixels need k > 2 (none k > 6).
    assert!(stats.max_k > 2, "the onion should need more than k = 2");
    assert!(
        stats.pixels_k_gt2 * 2 > stats.covered_pixels,
        "most onion pixels need k > 2"
    );
    let reference = reference::render(&mesh, &optics, &camera);
    let table = Table3d::build(&optics, 64, 64, mesh.quality().max_edge);
    let k_needed = (stats.max_k as usize).max(2);
    let (enough, errors_enough) =
        model_image(&geometry, &camera, &table, k_needed, TagScheme::Two, false);
    let (small, errors_small) = model_image(&geometry, &camera, &table, 2, TagScheme::Two, false);
    let (p_enough, p_small) = (psnr(&enough, &reference), psnr(&small, &reference));
    eprintln!(
        "k = {k_needed}: {p_enough:.2} dB, {errors_enough} out-of-order pops; k = 2: {p_small:.2} dB, {errors_small} pops"
    );
    assert_eq!(errors_enough, 0, "k = max k needed must sort every pixel");
    assert!(errors_small > 0);
    // Measured: 58.1 dB with the k it needs, 32.2 dB with k = 2 (356,488 out-of-order pops).
    assert!(p_enough > p_small + 20.0, "{p_enough} vs {p_small}");
}
