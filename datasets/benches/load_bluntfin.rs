//! Time to load Blunt Fin (PLOT3D XYZ + Q, 40,960 points → 187,395 tets) through
//! `datasets::load::load`: file reads, layout sniffing, bulk big-endian conversion, the 5-tet
//! split and the mesh checks of `TetMesh::new`. Goal: well under 0.2 s in release.
//! Needs the data directory (`TETBENCH_DATA`, default ../shared/datasets); without it the
//! bench prints why and measures nothing.

use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, Criterion};
use datasets::{load::load, LoadOptions};

fn data_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("TETBENCH_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/datasets"));
    dir.join("bluntfinxyz.bin").is_file().then_some(dir)
}

fn bench(c: &mut Criterion) {
    let Some(dir) = data_dir() else {
        eprintln!("SKIPPED: bluntfinxyz.bin not found (set TETBENCH_DATA to the data directory)");
        return;
    };
    let path = dir.join("bluntfinxyz.bin");
    let options = LoadOptions::default();
    let ds = load(&path, &options).expect("Blunt Fin loads");
    assert_eq!(ds.mesh.num_points(), 40_960);
    c.bench_function("load bluntfin (PLOT3D xyz+q → tets)", |b| {
        b.iter(|| load(std::hint::black_box(&path), &options).expect("Blunt Fin loads"))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
