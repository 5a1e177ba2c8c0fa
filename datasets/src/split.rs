//! The 1:8 regular refinement of a tet mesh: every tet is cut at its six edge midpoints into
//! four corner tets and four tets of the inner octahedron (Bey 1995). The scalar at a new point
//! is the mean of its edge's two end values, i.e. the linear field of the parent restricted to
//! the child, so the refined mesh carries exactly the same piecewise-linear field.
//!
//! This rebuilds the papers' refined data sets from the files we have: the ray-casting paper's
//! `spx1` is spx split once (12,936 · 8 = 103,488 tets), HAVS's and fragment PT's `spx2` spx
//! split twice (12,936 · 64 = 827,904 tets). Registry names take it as a modifier on any data
//! set: `NAME@split1`, `NAME@split2` (`@splitN`, N ≤ 4).

use std::collections::HashMap;

use rayon::prelude::*;

use crate::error::ErrorKind;
use crate::mesh::{signed_volume6, TetMesh};

/// The largest N accepted in `@splitN` (8⁴ = 4096 times the tets).
pub const MAX_SPLIT_LEVEL: u32 = 4;

/// Edges of a tet as vertex pairs, in the order the midpoints are numbered (m01, m02, m03,
/// m12, m13, m23).
const EDGES: [[usize; 2]; 6] = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]];

/// Midpoint slot (4 + index into [`EDGES`]) of the edge between corners `a` and `b`.
fn mid(a: usize, b: usize) -> usize {
    let (a, b) = (a.min(b), a.max(b));
    4 + EDGES.iter().position(|e| *e == [a, b]).unwrap_or(0)
}

/// Splits every tet of `mesh` 1:8 once. New points (one per unique edge) follow the original
/// points, numbered in order of first appearance; tet `t`'s children are tets `8t..8t+8`
/// (four corner tets, then the four octahedron tets), all positively oriented like their
/// parent. The octahedron is cut along its shortest diagonal, which keeps the children's
/// shapes from degrading over repeated splits.
pub fn split_once(mesh: &TetMesh) -> Result<TetMesh, ErrorKind> {
    let n_points = mesh.num_points();
    let mut edge_index: HashMap<(u32, u32), u32> = HashMap::with_capacity(mesh.num_tets() * 2);
    let mut points = mesh.points.clone();
    let mut scalars = mesh.scalars.clone();
    // Per tet the global indices of its 4 corners and 6 midpoints.
    let mut nodes: Vec<[u32; 10]> = Vec::with_capacity(mesh.num_tets());
    for t in &mesh.tets {
        let mut n = [0u32; 10];
        n[..4].copy_from_slice(t);
        for (e, [a, b]) in EDGES.iter().enumerate() {
            let (va, vb) = (t[*a], t[*b]);
            let key = (va.min(vb), va.max(vb));
            let idx = *edge_index.entry(key).or_insert_with(|| {
                let (pa, pb) = (mesh.points[va as usize], mesh.points[vb as usize]);
                points.push(std::array::from_fn(|c| {
                    ((pa[c] as f64 + pb[c] as f64) * 0.5) as f32
                }));
                scalars.push(
                    ((mesh.scalars[va as usize] as f64 + mesh.scalars[vb as usize] as f64) * 0.5)
                        as f32,
                );
                (points.len() - 1) as u32
            });
            n[4 + e] = idx;
        }
        nodes.push(n);
    }
    if points.len() > u32::MAX as usize {
        return Err(ErrorKind::IndexOverflow {
            what: "points after the 1:8 split".into(),
            count: points.len() as u64,
        });
    }
    debug_assert_eq!(points.len(), n_points + edge_index.len());
    let tets: Vec<[u32; 4]> = nodes
        .par_iter()
        .flat_map_iter(|n| children(n, &points))
        .collect();
    let mut out = TetMesh::new(
        mesh.name.clone(),
        points,
        scalars,
        mesh.scalar_name.clone(),
        tets,
    )?;
    out.repair.inverted_fixed += mesh.repair.inverted_fixed;
    out.repair.degenerate_dropped += mesh.repair.degenerate_dropped;
    Ok(out)
}

/// Splits `levels` times (0: a copy).
pub fn split(mesh: &TetMesh, levels: u32) -> Result<TetMesh, ErrorKind> {
    let mut m = mesh.clone();
    for _ in 0..levels {
        m = split_once(&m)?;
    }
    Ok(m)
}

/// The 8 children of one tet whose corners and midpoints are `n` (local slots as [`mid`]).
fn children(n: &[u32; 10], points: &[[f32; 3]]) -> [[u32; 4]; 8] {
    let p = |slot: usize| points[n[slot] as usize].map(|c| c as f64);
    // Corner tets: the parent scaled by ½ about each corner, vertices in the parent's order,
    // so they keep its orientation.
    let corner = |c: usize| -> [u32; 4] {
        std::array::from_fn(|i| if i == c { n[c] } else { n[mid(c, i)] })
    };
    // The octahedron's three diagonals join midpoints of opposite edges.
    let diagonals = [
        (mid(0, 1), mid(2, 3)),
        (mid(0, 2), mid(1, 3)),
        (mid(0, 3), mid(1, 2)),
    ];
    let len2 = |(a, b): (usize, usize)| {
        let (pa, pb) = (p(a), p(b));
        (0..3).map(|c| (pa[c] - pb[c]).powi(2)).sum::<f64>()
    };
    let (da, db) = diagonals
        .iter()
        .copied()
        .min_by(|x, y| len2(*x).total_cmp(&len2(*y)))
        .unwrap_or(diagonals[0]);
    // The other four midpoints form a ring around the diagonal; consecutive ones share a
    // corner of the parent (their edges meet), opposite ones do not.
    let ring_slots: Vec<usize> = (4..10).filter(|&s| s != da && s != db).collect();
    let edge_of = |s: usize| EDGES[s - 4];
    let adjacent = |s: usize, r: usize| {
        let (e, f) = (edge_of(s), edge_of(r));
        e.iter().any(|v| f.contains(v))
    };
    let r0 = ring_slots[0];
    let r1 = ring_slots[1..]
        .iter()
        .copied()
        .find(|&s| adjacent(r0, s))
        .unwrap_or(ring_slots[1]);
    let r2 = ring_slots[1..]
        .iter()
        .copied()
        .find(|&s| !adjacent(r0, s))
        .unwrap_or(ring_slots[2]);
    let r3 = ring_slots[1..]
        .iter()
        .copied()
        .find(|&s| s != r1 && s != r2)
        .unwrap_or(ring_slots[3]);
    let ring = [r0, r1, r2, r3];
    let inner = |i: usize| -> [u32; 4] {
        let slots = [da, db, ring[i], ring[(i + 1) % 4]];
        let v6 = signed_volume6(slots.map(p));
        if v6 < 0.0 {
            [n[slots[0]], n[slots[2]], n[slots[1]], n[slots[3]]]
        } else {
            slots.map(|s| n[s])
        }
    };
    [
        corner(0),
        corner(1),
        corner(2),
        corner(3),
        inner(0),
        inner(1),
        inner(2),
        inner(3),
    ]
}

/// Parses a modifier `splitN` (the part after `@`), N in 1..=[`MAX_SPLIT_LEVEL`].
pub fn parse_modifier(modifier: &str) -> Option<u32> {
    let n: u32 = modifier.trim().strip_prefix("split")?.parse().ok()?;
    (1..=MAX_SPLIT_LEVEL).contains(&n).then_some(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::linear_gradient;

    /// Two tets with even integer coordinates, so every midpoint (and its midpoints) is exact
    /// in f32 and volumes can be compared exactly.
    fn two_tets() -> TetMesh {
        let points = vec![
            [0.0, 0.0, 0.0],
            [8.0, 0.0, 0.0],
            [0.0, 8.0, 0.0],
            [0.0, 0.0, 8.0],
            [8.0, 8.0, 8.0],
        ];
        let scalars = vec![1.0, 3.0, -2.0, 0.5, 4.0];
        TetMesh::new("t", points, scalars, "s", vec![[0, 1, 2, 3], [1, 2, 3, 4]]).unwrap()
    }

    fn volume6(m: &TetMesh, t: usize) -> f64 {
        signed_volume6(m.tet_points(t))
    }

    #[test]
    fn counts_volume_orientation_and_linear_scalar() {
        let m = two_tets();
        for levels in 1..=2u32 {
            let s = split(&m, levels).unwrap();
            assert_eq!(s.num_tets(), m.num_tets() * 8usize.pow(levels));
            assert_eq!(s.repair.inverted_fixed, 0);
            assert_eq!(s.repair.degenerate_dropped, 0);
            assert_eq!(s.repair.unused_points, 0);
            let per = 8usize.pow(levels);
            for t in 0..m.num_tets() {
                let parent = volume6(&m, t);
                let kids: f64 = (0..per).map(|c| volume6(&s, t * per + c)).sum();
                assert_eq!(kids, parent, "level {levels} tet {t}");
                assert!((0..per).all(|c| volume6(&s, t * per + c) > 0.0));
                // Every child vertex carries the parent's linear field.
                let pp = m.tet_points(t);
                let ps = m.tets[t].map(|v| m.scalars[v as usize] as f64);
                let g = linear_gradient(pp, ps);
                for c in 0..per {
                    for &v in &s.tets[t * per + c] {
                        let q = s.points[v as usize].map(|x| x as f64);
                        let want = ps[0] + (0..3).map(|k| g[k] * (q[k] - pp[0][k])).sum::<f64>();
                        let got = s.scalars[v as usize] as f64;
                        assert!((got - want).abs() < 1e-5, "{got} vs {want}");
                    }
                }
            }
        }
        // One split: 5 points + 9 unique edges (6 + 6 − 3 shared).
        assert_eq!(split_once(&m).unwrap().num_points(), 5 + 9);
    }

    #[test]
    fn modifiers() {
        assert_eq!(parse_modifier("split1"), Some(1));
        assert_eq!(parse_modifier("split2"), Some(2));
        assert_eq!(parse_modifier("split0"), None);
        assert_eq!(parse_modifier("split9"), None);
        assert_eq!(parse_modifier("scale2"), None);
    }
}
