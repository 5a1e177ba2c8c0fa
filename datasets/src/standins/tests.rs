//! The stand-ins' sizes, seeds, volumes and the support split.

use super::*;
use crate::grid::GridValues;

#[test]
fn kuhn_split_is_conforming_and_positive() {
    let grid = VoxelGrid {
        dims: [4, 3, 5],
        spacing: [1.0, 0.5, 2.0],
        origin: [0.0; 3],
        values: vec![0.0; 60].into(),
        scalar_name: "z".into(),
    };
    let m = six_tet_mesh(&grid).unwrap();
    assert_eq!(m.num_tets(), 3 * 2 * 4 * 6);
    assert_eq!(m.repair.inverted_fixed, 0);
    assert_eq!(m.repair.degenerate_dropped, 0);
    let quads = 2 * (3 * 2 + 2 * 4 + 3 * 4);
    assert_eq!(m.boundary_faces().len(), 2 * quads);
    assert!(m.is_convex());
}

#[test]
fn domains_hit_exact_counts_and_cavities_make_them_non_convex() {
    for (shape, target) in [
        (Shape::Faceted, 20_011),
        (Shape::Box, 9_999),
        (Shape::Torso, 15_000),
    ] {
        let m = domain_mesh(shape, target, 3).unwrap();
        assert_eq!(m.num_tets(), target, "{shape:?}");
        assert_eq!(m.repair.degenerate_dropped, 0);
        assert_eq!(m.repair.unused_points, 0);
        if !shape.is_convex() {
            assert!(!m.is_convex(), "{shape:?}");
        }
    }
}

#[test]
fn large_volumes_split_only_their_support() {
    let g = splat_volume([12, 10, 9], 40, 3);
    let full = volume_tet_mesh_within(&g, usize::MAX).unwrap();
    assert_eq!(full.num_tets(), 11 * 9 * 8 * 6);
    let sparse = volume_tet_mesh_within(&g, 0).unwrap();
    let support = (0..8)
        .flat_map(|k| (0..9).flat_map(move |j| (0..11).map(move |i| (i, j, k))))
        // Counted here independently of `VoxelGrid::cube_has_nonzero_corner`.
        .filter(|&(i, j, k)| {
            (0..8).any(|b| {
                g.values
                    .get(g.index(i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1)))
                    != 0.0
            })
        })
        .count();
    assert!(support > 0 && support < 11 * 9 * 8);
    assert_eq!(sparse.num_tets(), support * 6);
    // Every grid point stays a mesh point, in grid order, so the grid can stand for them.
    assert_eq!(sparse.num_points(), g.num_voxels());
    assert_eq!(
        sparse.points[g.index(3, 2, 1)],
        g.point(3, 2, 1).map(|c| c as f32)
    );
    assert_eq!(sparse.repair.degenerate_dropped, 0);
    // Each non-zero voxel is a vertex of some tet of the support.
    let mut used = vec![false; g.num_voxels()];
    sparse
        .tets
        .iter()
        .flatten()
        .for_each(|&v| used[v as usize] = true);
    assert!(g.values.iter().zip(&used).all(|(v, &u)| v == 0.0 || u));
}

#[test]
fn standins_answer_to_the_papers_spellings() {
    for name in [
        "teapot",
        "standin:teapot",
        "BostonTeapot",
        "standin:BostonTeapot",
    ] {
        assert_eq!(find(name).map(|s| s.name), Some("teapot"), "{name}");
    }
    assert_eq!(find("standin:lobster").map(|s| s.name), Some("lobster"));
    assert!(find("standin:").is_none() && find("standin:nothing").is_none());
}

#[test]
fn splat_volumes_have_exactly_the_effective_voxels() {
    let g = splat_volume([20, 17, 9], 777, 5);
    assert_eq!(g.values.iter().filter(|&v| v != 0.0).count(), 777);
    assert!(matches!(g.values, GridValues::Levels { .. }));
    let r = resample_trilinear(&g, [7, 7, 7]);
    assert_eq!(r.values.len(), 343);
    assert_eq!(r.values.get(0), g.values.get(0));
}
