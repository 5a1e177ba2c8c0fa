//! Visibility orders: MPVONC gives a valid back-to-front order across
//! every interior face on convex acyclic meshes, from many viewpoints and both projections; the
//! centroid orders (radix, bucket, merge) satisfy their sort invariants; on non-convex meshes
//! MPVONC stays valid across interior faces.
//!
//! Validity is checked here independently of `render_core::visibility`: for each interior face,
//! its plane (from the tet's own vertices, outward normal by `TET_FACES` winding) tells which of
//! the two tets the eye sees it from; the other tet is behind and must come first.

use datasets::volume::structured_tets;
use datasets::{TetMesh, NO_NEIGHBOUR, TET_FACES};
use render_core::scene::{fixed_viewpoints, orbit_viewpoints};
use render_core::sort::{slab_of, DEFAULT_SLABS};
use render_core::visibility::{check_back_to_front, VisibilityOrder, VisibilitySorter};
use render_core::{Camera, Projection, Viewpoint};

/// Counter-based uniform in [0, 1) (SplitMix64), so tests do not depend on a crate's RNG.
fn uniform(seed: u64, i: u64) -> f64 {
    let mut z = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ i.wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

fn grid_points(dims: [usize; 3]) -> Vec<[f32; 3]> {
    let mut pts = Vec::new();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                pts.push([i as f32 * 0.9, j as f32 * 1.1, k as f32]);
            }
        }
    }
    pts
}

/// A structured-grid box, 5 tets per cell (convex).
fn grid_box(dims: [usize; 3]) -> TetMesh {
    let pts = grid_points(dims);
    let n = pts.len();
    TetMesh::new("box", pts, vec![0.0; n], "zero", structured_tets(dims)).unwrap()
}

/// A grid box with whole cells removed (a tunnel through the middle along z, a notch on one
/// side, and some cells at random), so the mesh stays conforming but is not convex.
fn grid_with_holes(dims: [usize; 3], seed: u64) -> TetMesh {
    let pts = grid_points(dims);
    let n = pts.len();
    let cells = [dims[0] - 1, dims[1] - 1, dims[2] - 1];
    let mut tets = Vec::new();
    for k in 0..cells[2] {
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                let tunnel = (i == cells[0] / 2 || i == cells[0] / 2 + 1) && j == cells[1] / 2;
                let notch = i == 0 && k >= cells[2] / 3 && k < 2 * cells[2] / 3;
                let c = (i + cells[0] * (j + cells[1] * k)) as u64;
                let random = uniform(seed, c) < 0.08;
                if !(tunnel || notch || random) {
                    tets.extend_from_slice(&datasets::volume::hex_cell_tets(dims, i, j, k));
                }
            }
        }
    }
    TetMesh::new("holes", pts, vec![0.0; n], "zero", tets).unwrap()
}

/// Circumcentre and squared radius of a tet (Cramer's rule on the bisector planes).
fn circumsphere(p: [[f64; 3]; 4]) -> ([f64; 3], f64) {
    let e: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|a| p[i + 1][a] - p[0][a]));
    let r: [f64; 3] =
        std::array::from_fn(|i| 0.5 * (e[i][0] * e[i][0] + e[i][1] * e[i][1] + e[i][2] * e[i][2]));
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let (c0, c1, c2) = (cross(e[1], e[2]), cross(e[2], e[0]), cross(e[0], e[1]));
    let det = e[0][0] * c0[0] + e[0][1] * c0[1] + e[0][2] * c0[2];
    let x: [f64; 3] = std::array::from_fn(|a| (r[0] * c0[a] + r[1] * c1[a] + r[2] * c2[a]) / det);
    (
        std::array::from_fn(|a| p[0][a] + x[a]),
        x[0] * x[0] + x[1] * x[1] + x[2] * x[2],
    )
}

/// The Delaunay tetrahedralisation of `count` random points in a box (Bowyer–Watson with a
/// bounding super-tetrahedron, whose tets are dropped at the end). Delaunay meshes have an
/// acyclic behind relation from every viewpoint (Edelsbrunner 1989), so MPVONC must be exact.
fn random_delaunay(count: usize, seed: u64) -> TetMesh {
    let mut pts: Vec<[f64; 3]> = (0..count as u64)
        .map(|i| {
            [
                uniform(seed, 3 * i),
                1.5 * uniform(seed, 3 * i + 1),
                0.8 * uniform(seed, 3 * i + 2),
            ]
        })
        .map(|p| p.map(|c| c as f32 as f64))
        .collect();
    pts.extend([
        [-10.0, -10.0, -10.0],
        [40.0, -10.0, -10.0],
        [-10.0, 40.0, -10.0],
        [-10.0, -10.0, 40.0],
    ]);
    let sup = count as u32;
    let mut tets: Vec<([u32; 4], [f64; 3], f64)> = Vec::new();
    let make = |t: [u32; 4], pts: &[[f64; 3]]| {
        let (c, r2) = circumsphere(t.map(|v| pts[v as usize]));
        (t, c, r2)
    };
    tets.push(make([sup, sup + 1, sup + 2, sup + 3], &pts));
    for v in 0..count as u32 {
        let p = pts[v as usize];
        let (bad, good): (Vec<_>, Vec<_>) = tets.into_iter().partition(|(_, c, r2)| {
            let d: f64 = (0..3).map(|a| (p[a] - c[a]).powi(2)).sum();
            d < *r2
        });
        let mut faces = std::collections::HashMap::new();
        for (t, _, _) in &bad {
            for f in TET_FACES {
                let mut k = f.map(|i| t[i]);
                k.sort_unstable();
                *faces.entry(k).or_insert(0) += 1;
            }
        }
        tets = good;
        for (f, c) in faces {
            if c == 1 {
                tets.push(make([f[0], f[1], f[2], v], &pts));
            }
        }
    }
    let cells: Vec<[u32; 4]> = tets
        .into_iter()
        .map(|(t, _, _)| t)
        .filter(|t| t.iter().all(|&v| v < sup))
        .collect();
    pts.truncate(count);
    let points: Vec<[f32; 3]> = pts.iter().map(|p| p.map(|c| c as f32)).collect();
    TetMesh::new("delaunay", points, vec![0.0; count], "zero", cells).unwrap()
}

/// Viewpoints: the 14 fixed ones, a 12-frame orbit and 12 random directions.
fn many_viewpoints(seed: u64) -> Vec<Viewpoint> {
    let mut v = fixed_viewpoints();
    v.extend(orbit_viewpoints(12));
    for i in 0..12u64 {
        let z = 2.0 * uniform(seed, 1000 + 2 * i) - 1.0;
        let a = std::f64::consts::TAU * uniform(seed, 1001 + 2 * i);
        let r = (1.0 - z * z).sqrt();
        v.push(Viewpoint::new(
            format!("random{i}"),
            [r * a.cos(), r * a.sin(), z],
        ));
    }
    v
}

fn cameras(mesh: &TetMesh, seed: u64) -> Vec<Camera> {
    let mut out = Vec::new();
    for vp in many_viewpoints(seed) {
        for proj in [Projection::default(), Projection::Orthographic] {
            out.push(Camera::fit(&mesh.bounds(), &vp, proj, 64, 64));
        }
    }
    // A close perspective camera (wide angle, strong perspective): where perspective and
    // centroid order differ most.
    let mut close = Camera::fit(
        &mesh.bounds(),
        &Viewpoint::new("close", [0.3, 0.5, 0.8]),
        Projection::Perspective { fovy_deg: 90.0 },
        64,
        64,
    );
    let c = mesh.bounds().center();
    close.eye = std::array::from_fn(|a| c[a] + (close.eye[a] - c[a]) * 0.45);
    out.push(close);
    out
}

/// Independent check: (interior faces that order their tets, faces where the order is wrong).
fn violations(mesh: &TetMesh, cam: &Camera, order: &[u32]) -> (usize, usize) {
    assert_eq!(order.len(), mesh.num_tets());
    let mut pos = vec![usize::MAX; mesh.num_tets()];
    for (i, &t) in order.iter().enumerate() {
        assert_eq!(pos[t as usize], usize::MAX, "tet {t} appears twice");
        pos[t as usize] = i;
    }
    let tol = 1e-9 * mesh.bounds().diagonal();
    let (mut faces, mut bad) = (0, 0);
    for (t, adj) in mesh.adjacency().iter().enumerate() {
        for (f, &nb) in adj.iter().enumerate() {
            if nb == NO_NEIGHBOUR || (nb as usize) < t {
                continue;
            }
            let [a, b, c] =
                TET_FACES[f].map(|l| mesh.points[mesh.tets[t][l] as usize].map(|x| x as f64));
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let to_eye = if cam.is_perspective() {
                [cam.eye[0] - a[0], cam.eye[1] - a[1], cam.eye[2] - a[2]]
            } else {
                cam.forward().map(|x| -x)
            };
            let s = (n[0] * to_eye[0] + n[1] * to_eye[1] + n[2] * to_eye[2]) / len;
            if s.abs() <= tol {
                continue; // edge-on: the face orders nothing
            }
            faces += 1;
            // The eye sees face f of t from outside t: the neighbour is in front, t behind.
            let (behind, front) = if s > 0.0 {
                (t, nb as usize)
            } else {
                (nb as usize, t)
            };
            if pos[behind] > pos[front] {
                bad += 1;
            }
        }
    }
    (faces, bad)
}

fn assert_mpvonc_exact(mesh: &TetMesh, seed: u64, expect_acyclic: bool) {
    let mut sorter = VisibilitySorter::new(VisibilityOrder::Mpvonc);
    let mut order = Vec::new();
    let mut total_faces = 0;
    for cam in cameras(mesh, seed) {
        let stats = sorter.back_to_front(mesh, &cam, &mut order);
        let (faces, bad) = violations(mesh, &cam, &order);
        total_faces += faces;
        if expect_acyclic {
            assert_eq!(
                stats.cycle_breaks,
                0,
                "{}: {} view {}: cycle",
                mesh.name,
                cam.viewpoint,
                cam.is_perspective()
            );
        }
        // Each broken cycle costs at most one face.
        assert!(
            bad <= stats.cycle_breaks,
            "{} view {} ({:?}): {bad} of {faces} faces out of order",
            mesh.name,
            cam.viewpoint,
            cam.projection
        );
        let lib = check_back_to_front(mesh, &cam, &order);
        assert_eq!(lib.violations, bad, "library check agrees");
        assert_eq!(stats.cells, mesh.num_tets());
    }
    assert!(total_faces > 0);
}

#[test]
fn mpvonc_is_exact_on_a_structured_box() {
    let mesh = grid_box([7, 6, 8]);
    assert!(mesh.is_convex());
    assert_mpvonc_exact(&mesh, 1, true);
}

#[test]
fn mpvonc_is_exact_on_random_delaunay_meshes() {
    for seed in 1..=3 {
        let mesh = random_delaunay(350, seed);
        assert!(mesh.num_tets() > 1500, "{} tets", mesh.num_tets());
        assert_mpvonc_exact(&mesh, seed, true);
    }
}

#[test]
fn centroid_orders_are_not_exact_but_mpvonc_is() {
    // The independent check must be able to fail: on an irregular mesh seen closely in
    // perspective, centroid order gets some faces wrong.
    let mesh = random_delaunay(350, 9);
    let mut radix = VisibilitySorter::new(VisibilityOrder::CentroidRadix);
    let mut order = Vec::new();
    let wrong: usize = cameras(&mesh, 9)
        .iter()
        .map(|cam| {
            radix.back_to_front(&mesh, cam, &mut order);
            violations(&mesh, cam, &order).1
        })
        .sum();
    assert!(
        wrong > 0,
        "centroid order happened to be exact everywhere: the check would be vacuous"
    );
}

#[test]
fn mpvonc_is_valid_across_interior_faces_of_non_convex_meshes() {
    for seed in [3, 4] {
        let mesh = grid_with_holes([9, 7, 8], seed);
        assert!(!mesh.is_convex());
        assert_mpvonc_exact(&mesh, seed, true);
    }
}

#[test]
fn centroid_orders_satisfy_their_sort_invariants() {
    let mesh = random_delaunay(300, 5);
    // The sorter keeps its centroids in f32 (the keys are f32 too).
    let centroid = |t: u32| {
        let p = mesh.tet_points(t as usize);
        [0, 1, 2].map(|a| (0.25 * (p[0][a] + p[1][a] + p[2][a] + p[3][a])) as f32 as f64)
    };
    let mut radix = VisibilitySorter::default();
    let mut merge = VisibilitySorter::new(VisibilityOrder::CentroidMerge);
    let mut bucket = VisibilitySorter::new(VisibilityOrder::CentroidBucket {
        slabs: DEFAULT_SLABS,
    });
    let (mut r, mut m, mut b) = (Vec::new(), Vec::new(), Vec::new());
    for cam in cameras(&mesh, 5) {
        let first = radix.back_to_front(&mesh, &cam, &mut r);
        merge.back_to_front(&mesh, &cam, &mut m);
        bucket.back_to_front(&mesh, &cam, &mut b);
        assert_eq!(first.order, VisibilityOrder::CentroidRadix);
        let key = |t: u32| cam.sort_distance(centroid(t)) as f32;
        for order in [&r, &m, &b] {
            let mut seen = order.clone();
            seen.sort_unstable();
            assert_eq!(
                seen,
                (0..mesh.num_tets() as u32).collect::<Vec<_>>(),
                "a permutation"
            );
        }
        // Radix and merge: keys never increase; both stable, so they agree exactly.
        assert!(r.windows(2).all(|w| key(w[0]) >= key(w[1])));
        assert!(m.windows(2).all(|w| key(w[0]) >= key(w[1])));
        assert_eq!(r, m);
        // Bucket: slabs never increase; inside a slab the tets keep their id order.
        let keys: Vec<f32> = (0..mesh.num_tets() as u32).map(key).collect();
        let lo = keys.iter().copied().fold(f32::INFINITY, f32::min);
        let hi = keys.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let slab = |t: u32| slab_of(key(t), lo, hi, DEFAULT_SLABS);
        for w in b.windows(2) {
            assert!(slab(w[0]) >= slab(w[1]));
            if slab(w[0]) == slab(w[1]) {
                assert!(w[0] < w[1]);
            }
        }
    }
    // Per-mesh data is computed once: the next call on the same mesh reuses it.
    let cam = Camera::fit(
        &mesh.bounds(),
        &fixed_viewpoints()[0],
        Projection::default(),
        64,
        64,
    );
    assert_eq!(radix.back_to_front(&mesh, &cam, &mut r).precompute_ms, 0.0);
}

#[test]
fn mpvonc_handles_a_second_mesh_and_order_switches() {
    let a = grid_box([4, 4, 4]);
    let b = grid_with_holes([6, 5, 5], 1);
    let mut sorter = VisibilitySorter::new(VisibilityOrder::Mpvonc);
    let cam_a = Camera::fit(
        &a.bounds(),
        &fixed_viewpoints()[7],
        Projection::default(),
        32,
        32,
    );
    let cam_b = Camera::fit(
        &b.bounds(),
        &fixed_viewpoints()[9],
        Projection::default(),
        32,
        32,
    );
    let mut order = Vec::new();
    for (mesh, cam) in [(&a, &cam_a), (&b, &cam_b), (&a, &cam_a)] {
        for o in VisibilityOrder::ALL {
            sorter.set_order(o);
            let stats = sorter.back_to_front(mesh, cam, &mut order);
            assert_eq!(order.len(), mesh.num_tets());
            if o == VisibilityOrder::Mpvonc {
                assert_eq!(violations(mesh, cam, &order).1, 0);
                assert!(stats.entry_faces > 0);
            }
        }
    }
}

#[test]
fn mpvonc_with_the_eye_inside_the_mesh() {
    // No boundary face faces the eye, so no entry cell exists: every tet is reached from the
    // fallback roots (decreasing centroid distance), and the order stays exact.
    let mesh = random_delaunay(300, 11);
    let c = mesh.bounds().center();
    let mut cam = Camera::fit(
        &mesh.bounds(),
        &fixed_viewpoints()[8],
        Projection::default(),
        64,
        64,
    );
    cam.eye = [c[0] + 0.01, c[1] - 0.02, c[2] + 0.03];
    let mut sorter = VisibilitySorter::new(VisibilityOrder::Mpvonc);
    let mut order = Vec::new();
    let stats = sorter.back_to_front(&mesh, &cam, &mut order);
    assert_eq!(stats.entry_faces, 0);
    assert_eq!(stats.unreached, mesh.num_tets());
    assert_eq!(stats.cycle_breaks, 0);
    assert_eq!(violations(&mesh, &cam, &order).1, 0);
}
