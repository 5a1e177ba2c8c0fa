//! Generated meshes: `.vtu` round trips are exact, generation is deterministic, sizes are as
//! documented, the non-convex generators really are non-convex (rays re-enter), the sliver
//! generator is sliver-rich yet valid, and resampling onto a voxel grid is exact for linear
//! fields.

use datasets::generate::{box_cells, from_spec, shell_cells};
use datasets::mesh::signed_volume6;
use datasets::write_vtu::{write_vtu, write_vtu_with, VtuFormat, VtuOptions};
use datasets::{LoadOptions, TetMesh, VoxelGrid};

fn same_mesh(a: &TetMesh, b: &TetMesh, what: &str) {
    assert_eq!(a.points, b.points, "{what}: points");
    assert_eq!(a.scalars, b.scalars, "{what}: scalars");
    assert_eq!(a.tets, b.tets, "{what}: tets");
    assert_eq!(a.scalar_name, b.scalar_name, "{what}: scalar name");
    assert_eq!(a.content_hash(), b.content_hash(), "{what}: hash");
}

fn total_volume(m: &TetMesh) -> f64 {
    (0..m.num_tets())
        .map(|t| signed_volume6(m.tet_points(t)) / 6.0)
        .sum()
}

/// Number of boundary triangles a ray crosses (Möller–Trumbore, f64).
fn boundary_crossings(m: &TetMesh, o: [f64; 3], d: [f64; 3]) -> usize {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    m.boundary_faces()
        .iter()
        .filter(|f| {
            let [a, b, c] = f
                .vertices(m)
                .map(|v| m.points[v as usize].map(|x| x as f64));
            let (e1, e2) = (sub(b, a), sub(c, a));
            let p = cross(d, e2);
            let det = dot(e1, p);
            if det.abs() < 1e-14 {
                return false;
            }
            let s = sub(o, a);
            let u = dot(s, p) / det;
            let q = cross(s, e1);
            let v = dot(d, q) / det;
            let t = dot(e2, q) / det;
            (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && t > 0.0
        })
        .count()
}

#[test]
fn every_generator_round_trips_through_vtu() {
    let dir = tempfile::tempdir().unwrap();
    let specs = [
        "box:1k",
        "box:20k:field=blobs",
        "box:5k:field=radial",
        "box:3k:field=linear:seed=9",
        "shell:2k",
        "shell:12k:field=ml",
        "tunnels:5k",
        "tunnels:15k:field=blobs",
        "slivers:1k",
        "slivers:25k:field=ml",
    ];
    for (i, spec) in specs.iter().enumerate() {
        for seed in [1u64, 42] {
            let mesh = from_spec(spec, seed).unwrap();
            assert_eq!(mesh.repair.degenerate_dropped, 0, "{spec}");
            let path = dir.path().join(format!("g{i}_{seed}.vtu"));
            write_vtu(&mesh, &path).unwrap();
            let back = datasets::load::load(&path, &LoadOptions::default()).unwrap();
            same_mesh(&mesh, &back.mesh, spec);
            assert_eq!(
                back.mesh.repair.inverted_fixed, 0,
                "{spec}: written tets are already positive"
            );
        }
    }
    // The other layouts ParaView reads give the same mesh too.
    let mesh = from_spec("shell:3k:field=blobs", 3).unwrap();
    for format in [
        VtuFormat::Ascii,
        VtuFormat::Binary,
        VtuFormat::AppendedBase64,
    ] {
        let path = dir.path().join("layout.vtu");
        write_vtu_with(
            &mesh,
            &path,
            &VtuOptions {
                format,
                compress: format != VtuFormat::Ascii,
                ..Default::default()
            },
        )
        .unwrap();
        let back = datasets::load::load(&path, &LoadOptions::default()).unwrap();
        same_mesh(&mesh, &back.mesh, &format!("{format:?}"));
    }
}

#[test]
fn generation_is_deterministic_and_seeded() {
    for spec in [
        "box:2k:field=blobs",
        "shell:2k",
        "tunnels:3k:field=blobs",
        "slivers:2k",
    ] {
        let a = from_spec(spec, 7).unwrap();
        let b = from_spec(spec, 7).unwrap();
        same_mesh(&a, &b, spec);
        let c = from_spec(spec, 8).unwrap();
        assert_ne!(
            a.content_hash(),
            c.content_hash(),
            "{spec}: the seed must matter"
        );
    }
    // A seed in the spec overrides the argument; the ML field does not depend on the seed.
    same_mesh(
        &from_spec("box:2k:field=blobs:seed=3", 1).unwrap(),
        &from_spec("box:2k:field=blobs", 3).unwrap(),
        "seed=",
    );
    same_mesh(
        &from_spec("box:2k", 1).unwrap(),
        &from_spec("box:2k", 2).unwrap(),
        "ml",
    );
}

#[test]
fn generated_sizes_are_exact_and_near_the_target() {
    for (spec, target) in [
        ("box:1k", 1_000),
        ("box:10k", 10_000),
        ("box:100k", 100_000),
        ("slivers:30k", 30_000),
    ] {
        let m = from_spec(spec, 1).unwrap();
        let c = box_cells(target);
        assert_eq!(m.num_tets(), 5 * c[0] * c[1] * c[2], "{spec}");
        assert_eq!(
            m.num_points(),
            (c[0] + 1) * (c[1] + 1) * (c[2] + 1),
            "{spec}"
        );
        assert!(
            (m.num_tets() as f64 / target as f64 - 1.0).abs() < 0.03,
            "{spec}: {}",
            m.num_tets()
        );
    }
    // The shell puts cell shape before count (tests/generator_quality.rs has the bounds).
    for (spec, target, tolerance) in [("shell:2k", 2_000, 0.25), ("shell:50k", 50_000, 0.10)] {
        let m = from_spec(spec, 1).unwrap();
        let (n, l) = shell_cells(target);
        assert_eq!(m.num_tets(), 36 * n * n * l, "{spec}");
        assert!(
            (m.num_tets() as f64 / target as f64 - 1.0).abs() < tolerance,
            "{spec}: {}",
            m.num_tets()
        );
    }
    let m = from_spec("tunnels:20k", 1).unwrap();
    assert!(
        (m.num_tets() as f64 / 20_000.0 - 1.0).abs() < 0.06,
        "tunnels: {}",
        m.num_tets()
    );
    assert_eq!(m.repair.unused_points, 0);
}

#[test]
fn box_is_a_conforming_convex_cube() {
    let m = from_spec("box:5k", 1).unwrap();
    let c = box_cells(5_000);
    assert!((total_volume(&m) - 8.0).abs() < 1e-6);
    let quads = 2 * (c[0] * c[1] + c[1] * c[2] + c[0] * c[2]);
    assert_eq!(m.boundary_faces().len(), 2 * quads);
    assert!(m.is_convex());
    assert_eq!(
        boundary_crossings(&m, [-3.0, 0.0123, 0.0371], [1.0, 0.0, 0.0]),
        2
    );
    // Marschner–Lobb spans [0, 1].
    let (lo, hi) = m.scalar_range();
    assert!(lo >= 0.0 && hi <= 1.0 && hi - lo > 0.8, "{lo} {hi}");
}

#[test]
fn shell_and_tunnels_are_non_convex_and_rays_re_enter() {
    let m = from_spec("shell:20k", 1).unwrap();
    let (n, _) = shell_cells(20_000);
    assert!(!m.is_convex());
    // Closed, conforming surfaces: n×n quads per cube face, outer and inner sphere.
    assert_eq!(m.boundary_faces().len(), 2 * 2 * 6 * n * n);
    // Volume of the polyhedral shell: a little under 4/3·π·(1 − 0.5³).
    let v = total_volume(&m);
    let exact = 4.0 / 3.0 * std::f64::consts::PI * (1.0 - 0.125);
    assert!(v < exact && v > 0.95 * exact, "{v} vs {exact}");
    assert_eq!(
        boundary_crossings(&m, [-3.0, 0.0123, 0.0371], [1.0, 0.0, 0.0]),
        4
    );
    assert_eq!(
        boundary_crossings(&m, [0.0137, -3.0, 0.0211], [0.0, 1.0, 0.0]),
        4
    );

    let t = from_spec("tunnels:30k", 1).unwrap();
    assert!(!t.is_convex());
    // Along x at y = 0.45 the ray crosses the two z-tunnels at x = ±0.45: 6 crossings.
    assert_eq!(
        boundary_crossings(&t, [-3.0, 0.4513, 0.0171], [1.0, 0.0, 0.0]),
        6
    );
    assert_eq!(
        boundary_crossings(&t, [-3.0, 0.0113, 0.0171], [1.0, 0.0, 0.0]),
        2
    );
}

#[test]
fn slivers_are_many_and_the_mesh_stays_valid() {
    let m = from_spec("slivers:20k", 1).unwrap();
    let q = m.quality();
    assert!(
        q.slivers * 4 > m.num_tets(),
        "only {} slivers of {}",
        q.slivers,
        m.num_tets()
    );
    assert!(q.max_aspect_ratio > 50.0, "{}", q.max_aspect_ratio);
    // No overlaps (sum of positive volumes = the cube), no degenerate tets, conforming.
    assert_eq!(m.repair.degenerate_dropped, 0);
    assert!(
        (total_volume(&m) - 8.0).abs() < 1e-5,
        "{}",
        total_volume(&m)
    );
    let c = box_cells(20_000);
    assert_eq!(
        m.boundary_faces().len(),
        4 * (c[0] * c[1] + c[1] * c[2] + c[0] * c[2])
    );
    // A plain box has none.
    assert_eq!(from_spec("box:20k", 1).unwrap().quality().slivers, 0);
}

#[test]
fn resampling_reproduces_linear_fields() {
    let f = |p: [f64; 3]| 0.3 + 0.5 * p[0] - 0.25 * p[1] + 0.125 * p[2];
    let m = from_spec("box:4k:field=linear", 1).unwrap();
    let vg = VoxelGrid::resample(&m, [9, 7, 5]);
    assert_eq!(vg.values.len(), 9 * 7 * 5);
    for k in 0..5 {
        for j in 0..7 {
            for i in 0..9 {
                let v = vg.values.get(vg.index(i, j, k)) as f64;
                assert!(
                    (v - f(vg.point(i, j, k))).abs() < 2e-6,
                    "({i},{j},{k}): {v}"
                );
            }
        }
    }
    // Through a hollow mesh: exact inside the material, the minimum scalar in the cavity.
    let s = from_spec("shell:30k:field=linear", 1).unwrap();
    let vg = VoxelGrid::resample(&s, [21, 21, 21]);
    let (lo, _) = s.scalar_range();
    let (mut inside, mut cavity) = (0, 0);
    for k in 0..21 {
        for j in 0..21 {
            for i in 0..21 {
                let p = vg.point(i, j, k);
                let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                let v = vg.values.get(vg.index(i, j, k)) as f64;
                if r > 0.6 && r < 0.9 {
                    inside += 1;
                    assert!((v - f(p)).abs() < 2e-6, "{p:?}: {v}");
                } else if !(0.4..=1.1).contains(&r) {
                    cavity += 1;
                    assert_eq!(v as f32, lo, "{p:?}");
                }
            }
        }
    }
    assert!(inside > 1000 && cavity > 100, "{inside} {cavity}");
}

#[test]
fn voxel_grid_to_tets() {
    let vg = VoxelGrid {
        dims: [4, 3, 5],
        spacing: [0.5, 1.0, 2.0],
        origin: [1.0, 2.0, 3.0],
        values: (0..60).map(|v| v as f32).collect::<Vec<_>>().into(),
        scalar_name: "v".into(),
    };
    let m = vg.to_tets().unwrap();
    assert_eq!(m.num_tets(), 5 * 3 * 2 * 4);
    assert_eq!(m.points[vg.index(3, 2, 4)], [2.5, 4.0, 11.0]);
    assert_eq!(m.scalars, vg.values.to_vec());
    assert!((total_volume(&m) - 1.5 * 2.0 * 8.0).abs() < 1e-9);
    // And back: resampling on its own lattice returns the voxel values.
    let back = VoxelGrid::resample(&m, vg.dims);
    assert_eq!(back.origin, vg.origin);
    for (a, b) in back.values.iter().zip(vg.values.iter()) {
        assert!((a - b).abs() < 1e-4, "{a} {b}");
    }
    let bad = VoxelGrid {
        values: vec![0.0; 3].into(),
        ..vg
    };
    assert!(bad.to_tets().is_err());
}

/// A large stand-in volume's mesh splits only its support (the cubes with a non-zero corner).
/// Seen with the same camera and optics, it renders like the whole grid's split under a transfer
/// function with κ(0) = 0: the cubes left out hold 0 at every corner and so add nothing. (The
/// harness fits camera and optics to each mesh's own bounds, so a run frames the support.)
#[test]
fn support_split_renders_like_the_full_split_when_zero_is_empty() {
    use datasets::standins::{six_tet_mesh, splat_volume, volume_tet_mesh_within};
    use render_core::{Optics, Projection, TransferFunction};
    use tetbench_tests::{camera, psnr, view};

    let grid = splat_volume([14, 12, 10], 150, 7);
    let full = six_tet_mesh(&grid).unwrap();
    let support = volume_tet_mesh_within(&grid, 0).unwrap();
    assert!(
        support.num_tets() < full.num_tets() / 2,
        "{}",
        support.num_tets()
    );
    let optics = Optics::for_mesh(TransferFunction::preset("zero-floor").unwrap(), &full);
    for dir in [[1.0, 0.0, 0.0], [1.0, 1.0, 1.0], [-1.0, 0.5, -0.3]] {
        let cam = camera(&full, &view(dir), Projection::default(), 48);
        let a = reference::render(&full, &optics, &cam);
        let b = reference::render(&support, &optics, &cam);
        let worst = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .flat_map(|(p, q)| p.iter().zip(q).map(|(x, y)| (x - y).abs()))
            .fold(0.0f32, f32::max);
        assert!(a.pixels.iter().any(|p| p[3] > 0.01), "{dir:?}: empty image");
        // f32 output of two f64 walks that cross different (empty) tets: rounding only.
        assert!(
            worst < 1e-5,
            "{dir:?}: largest channel difference {worst} ({} dB)",
            psnr(&a, &b)
        );
    }
}
