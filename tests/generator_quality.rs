//! Every quality generator (`box`, `shell`, `tunnels`) gives, at every size of the sweep, a mesh
//! of the shape it promises with no slivers (aspect ratio ≤ `generate::MAX_ASPECT`); `onion` is
//! the sliver stress case on purpose. `shell:10k` used to be 10,008 slivers.

use datasets::generate::{from_spec, shell_cells, Kind, MAX_ASPECT};
use datasets::TetMesh;

const SIZES: [&str; 6] = ["1k", "2k", "5k", "10k", "50k", "1m"];

fn radius(p: [f32; 3]) -> f64 {
    p.iter()
        .map(|&c| (c as f64) * (c as f64))
        .sum::<f64>()
        .sqrt()
}

fn volume(m: &TetMesh) -> f64 {
    (0..m.num_tets())
        .map(|t| datasets::mesh::signed_volume6(m.tet_points(t)) / 6.0)
        .sum()
}

fn check_quality(spec: &str, m: &TetMesh) {
    let q = m.quality();
    eprintln!(
        "{spec}: {} tets, {} boundary faces, max aspect {:.2}, mean {:.2}",
        m.num_tets(),
        m.boundary_faces().len(),
        q.max_aspect_ratio,
        q.mean_aspect_ratio
    );
    assert_eq!(q.slivers, 0, "{spec}: slivers");
    assert!(
        q.max_aspect_ratio <= MAX_ASPECT,
        "{spec}: max aspect ratio {} > {MAX_ASPECT}",
        q.max_aspect_ratio
    );
    assert_eq!(m.repair.degenerate_dropped, 0, "{spec}");
}

#[test]
fn box_is_a_convex_cube_without_slivers_at_every_size() {
    for size in SIZES {
        let spec = format!("box:{size}");
        let m = from_spec(&spec, 1).unwrap();
        check_quality(&spec, &m);
        assert!(m.is_convex(), "{spec}");
        assert!((volume(&m) - 8.0).abs() < 1e-4, "{spec}: {}", volume(&m));
    }
}

#[test]
fn shell_is_a_hollow_sphere_without_slivers_at_every_size() {
    let (r0, r1) = datasets::generate::SHELL_RADII;
    for size in SIZES {
        let spec = format!("shell:{size}");
        let target = datasets::generate::parse_size(size).unwrap();
        let m = from_spec(&spec, 1).unwrap();
        check_quality(&spec, &m);
        let (n, layers) = shell_cells(target);
        assert_eq!(m.num_tets(), 36 * n * n * layers, "{spec}");
        // Shape before count (see `shell_cells`): within 25 % of the target below 10 k tets,
        // 10 % below 100 k, 5 % from there up.
        let tolerance = if target < 10_000 {
            0.25
        } else if target < 100_000 {
            0.10
        } else {
            0.05
        };
        let rel = m.num_tets() as f64 / target as f64 - 1.0;
        assert!(rel.abs() <= tolerance, "{spec}: {} tets", m.num_tets());
        // A real cavity and a curved outer surface: the boundary is the inner and the outer
        // sphere (2 × 6n² quads, 2 triangles each), every boundary point on one of them, with
        // at least 4 cells per quarter circle.
        assert!(!m.is_convex(), "{spec}");
        assert!(n >= 4, "{spec}: only {n} cells per cube-face edge");
        assert_eq!(m.boundary_faces().len(), 24 * n * n, "{spec}");
        let (mut inner, mut outer) = (0, 0);
        for f in m.boundary_faces() {
            for v in f.vertices(&m) {
                let r = radius(m.points[v as usize]);
                if (r - r0).abs() < 1e-5 {
                    inner += 1;
                } else if (r - r1).abs() < 1e-5 {
                    outer += 1;
                } else {
                    panic!("{spec}: boundary point at radius {r}");
                }
            }
        }
        assert_eq!(inner, outer, "{spec}");
        // The polyhedral shell's volume approaches 4/3·π·(r1³ − r0³) from below.
        let exact = 4.0 / 3.0 * std::f64::consts::PI * (r1.powi(3) - r0.powi(3));
        let v = volume(&m);
        assert!(
            v < exact && v > 0.85 * exact,
            "{spec}: volume {v} of {exact}"
        );
    }
}

/// Whether point `p` lies in tet `t` (barycentric signs, with a little slack for round-off).
fn contains(m: &TetMesh, t: usize, p: [f64; 3]) -> bool {
    let q = m.tet_points(t);
    let lo = (0..3).map(|a| q.iter().map(|v| v[a]).fold(f64::MAX, f64::min));
    let hi = (0..3).map(|a| q.iter().map(|v| v[a]).fold(f64::MIN, f64::max));
    if lo
        .zip(hi)
        .zip(p)
        .any(|((l, h), x)| x < l - 1e-9 || x > h + 1e-9)
    {
        return false;
    }
    let whole = datasets::mesh::signed_volume6(q);
    (0..4).all(|i| {
        let mut r = q;
        r[i] = p;
        datasets::mesh::signed_volume6(r) >= -1e-12 * whole.abs()
    })
}

#[test]
fn tunnels_are_open_and_without_slivers_at_every_size() {
    for size in SIZES {
        let spec = format!("tunnels:{size}");
        let m = from_spec(&spec, 1).unwrap();
        check_quality(&spec, &m);
        assert!(!m.is_convex(), "{spec}");
        // Each of the 12 tunnels is open: points along its axis line lie in no tet.
        for (axis, u, v) in datasets::generate::TUNNEL_LINES {
            for step in 0..9 {
                let mut p = [0.0; 3];
                p[axis] = -0.8 + 0.2 * step as f64;
                p[(axis + 1) % 3] = u;
                p[(axis + 2) % 3] = v;
                let inside = (0..m.num_tets()).find(|&t| contains(&m, t, p));
                assert!(
                    inside.is_none(),
                    "{spec}: tunnel point {p:?} is in tet {inside:?}"
                );
            }
        }
    }
}

/// `onion` is the old degenerate shell, kept as a named stress case: every tet a sliver.
#[test]
fn onion_is_all_slivers() {
    let m = from_spec("onion:10k", 1).unwrap();
    assert_eq!(m.num_tets(), 36 * 278);
    assert_eq!(m.boundary_faces().len(), 24);
    assert_eq!(m.quality().slivers, m.num_tets());
    assert!(!m.is_convex());
    assert!(Kind::ALL.contains(&Kind::Onion));
}
