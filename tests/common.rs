//! Helpers shared by the cross-crate tests: the data directory, and the set-up every
//! `*_vs_reference.rs` repeats (GPU, meshes, optics, cameras, the reference image, the image
//! error). The image error is the harness's own ([`render_core::image_error`], re-exported as
//! `harness::results::metrics`): a PSNR in a test means what it means in `results.csv`.

use std::path::PathBuf;

use std::sync::Arc;

use datasets::TetMesh;
use render_core::{Camera, Gpu, Image, Optics, Projection, TransferFunction, Viewpoint};

pub use render_core::image_error::{compare, psnr, psnr_from_rmse, ImageError, PSNR_CAP_DB};

#[path = "malformed_vtk.rs"]
pub mod malformed_vtk;

/// Runs `python3 scripts/NAME ARGS…` from the workspace root: whether it succeeded, and its
/// stdout and stderr together (the structure checks, `module_cycles.rs` and `code_limits.rs`).
pub fn run_script(name: &str, args: &[&std::ffi::OsStr]) -> (bool, String) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = std::process::Command::new("python3")
        .arg(root.join("scripts").join(name))
        .args(args)
        .current_dir(&root)
        .output()
        .unwrap_or_else(|e| panic!("python3 runs scripts/{name} (install python3): {e}"));
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.success(), text)
}

/// The data directory of the papers' data sets, or `None` (and a printed reason) when absent;
/// with `TETBENCH_REQUIRE_DATA=1` a missing directory fails the test instead
/// (`datasets::registry::test_data_file`).
pub fn data_dir() -> Option<PathBuf> {
    datasets::registry::test_data_file("MANIFEST.md").and_then(|p| p.parent().map(PathBuf::from))
}

/// One file of the data directory, or `None` with a printed skip (a failure under
/// `TETBENCH_REQUIRE_DATA=1`).
pub fn data_file(name: &str) -> Option<PathBuf> {
    datasets::registry::test_data_file(name)
}

/// SPX (12,936 tets) from the data directory, or `None` with a printed skip.
pub fn spx() -> Option<Arc<TetMesh>> {
    let path = data_file("spx.vtk")?;
    let mesh = datasets::load::load(&path, &Default::default())
        .unwrap_or_else(|e| panic!("{}: {e:#}", path.display()))
        .mesh;
    assert_eq!(mesh.num_tets(), 12936, "{}", path.display());
    Some(Arc::new(mesh))
}

/// The headless GPU (lavapipe where there is no other); wgpu wants `XDG_RUNTIME_DIR`.
pub fn gpu() -> Gpu {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", "/tmp");
    }
    Gpu::new().expect("a wgpu adapter (lavapipe: apt-get install mesa-vulkan-drivers)")
}

/// A preset transfer function's optics fitted to `mesh`'s scalar range and size.
pub fn optics(mesh: &TetMesh, preset: &str) -> Optics {
    Optics::for_mesh(TransferFunction::preset(preset).unwrap(), mesh)
}

/// A `size`² camera fitted to `mesh` from `viewpoint`.
pub fn camera(mesh: &TetMesh, viewpoint: &Viewpoint, projection: Projection, size: u32) -> Camera {
    Camera::fit(&mesh.bounds(), viewpoint, projection, size, size)
}

/// The viewpoint along `dir`, named by its signs (`+x+y+z`, `-y`).
pub fn view(dir: [f64; 3]) -> Viewpoint {
    let mut name = String::new();
    for (v, axis) in dir.iter().zip(['x', 'y', 'z']) {
        if *v != 0.0 {
            name.push(if *v > 0.0 { '+' } else { '-' });
            name.push(axis);
        }
    }
    Viewpoint::new(name, dir)
}

/// One picture to check: mesh, optics, camera and the exact reference image.
pub struct Scene<'a> {
    pub mesh: &'a Arc<TetMesh>,
    pub optics: &'a Optics,
    pub camera: Camera,
    pub reference: Image,
}

impl<'a> Scene<'a> {
    pub fn new(mesh: &'a Arc<TetMesh>, optics: &'a Optics, camera: Camera) -> Self {
        let reference = reference::render(mesh, optics, &camera);
        Scene {
            mesh,
            optics,
            camera,
            reference,
        }
    }

    /// PSNR of `image` against this scene's reference (the harness's definition).
    pub fn psnr(&self, image: &Image) -> f64 {
        psnr(image, &self.reference)
    }
}

/// Fails on a NaN or infinite channel (the image error would count it as maximal, but a
/// non-finite value is a defect on its own).
pub fn assert_finite(image: &Image, what: &str) {
    if let Some(i) = image
        .pixels
        .iter()
        .position(|p| p.iter().any(|v| !v.is_finite()))
    {
        panic!(
            "{what}: pixel ({}, {}) is {:?}",
            i as u32 % image.width,
            i as u32 / image.width,
            image.pixels[i]
        );
    }
}

/// RMSE of two images as [`compare`] measures it (RGB, clamped, every pixel).
pub fn rmse(a: &Image, b: &Image) -> f64 {
    compare(a, b).unwrap().rmse
}

/// A 12³-point grid (6,655 tets) with a smooth field that crosses most of the transfer
/// function's range: convex, so every visibility order is right and the error left is the
/// algorithm's own approximation.
pub fn grid_mesh() -> Arc<TetMesh> {
    let n = 12;
    let mut points = Vec::new();
    let mut scalars = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = [
                    i as f32 / (n - 1) as f32,
                    j as f32 / (n - 1) as f32 * 0.8,
                    k as f32 / (n - 1) as f32 * 0.9,
                ];
                let r2 = (p[0] - 0.5).powi(2) + (p[1] - 0.4).powi(2) + (p[2] - 0.45).powi(2);
                scalars.push((-4.0 * r2).exp() + 0.3 * (3.0 * p[0]).sin() * p[2]);
                points.push(p);
            }
        }
    }
    Arc::new(
        TetMesh::new(
            "grid",
            points,
            scalars,
            "f",
            datasets::volume::structured_tets([n, n, n]),
        )
        .unwrap(),
    )
}

/// A comb: a base bar with teeth one cell wide and one cell thick, cut from a structured grid.
/// Rays from a diagonal leave and re-enter the mesh between teeth, and cross the corner tets
/// of a tooth entering and leaving through two boundary faces of the same tet — the case the
/// single tag of HAVS gets wrong (Callahan et al. 2005, §4).
pub fn comb_mesh() -> Arc<TetMesh> {
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
    Arc::new(TetMesh::new("comb", points, scalars, "f", tets).unwrap())
}

/// A renderer's per-frame counter by name (NaN when absent, so a comparison with it fails).
pub fn counter(counters: &[(String, f64)], name: &str) -> f64 {
    counters
        .iter()
        .find(|(n, _)| n == name)
        .map_or(f64::NAN, |c| c.1)
}
