//! The CPU twin (f64) of the classification the vertex shader performs (`gator.wgsl`,
//! `project_and_classify`): the same tests, table and arithmetic, so tests can check the GPU.
//!
//! Wylie et al. 2002, §3: the projection of a tetrahedron is drawn as one *basis graph*, a fan
//! around a "thick" (phantom) vertex. Which of the 4 vertices goes to which node of the graph
//! is chosen by four tests (Fig. 5):
//!
//! * Test 1: v1 lies "between" v2 and v3 seen from v0 — the line v0v1 separates v2 and v3
//!   (the z components of (v1−v0)×(v2−v0) and (v1−v0)×(v3−v0) differ in sign);
//! * Test 2: v2 lies between v1 and v3 — the line v0v2 separates v1 and v3;
//! * Test 3: v2 is counter-clockwise from v1 around v0 ((v1−v0)×(v2−v0) > 0);
//! * Test 4 (after the remapping of tests 1–3): the diagonals v0'v1' and v2'v3' intersect
//!   inside v0'v1', i.e. all four points are on the convex hull (Shirley–Tuchman class 2);
//!   otherwise v1' lies inside the triangle v0'v2'v3' (class 1).
//!
//! Tests 1–3 pick one of 8 permutations (the authors' `MappingTable`, gator.cg) that puts the
//! vertex whose ray from v0 lies between the other two into slot v1', so that the hull is
//! v0', v3', v1', v2' (or the triangle v0', v3', v2' with v1' inside). With test 4 that is
//! 16 combinations of which 2 cannot occur (v0 strictly inside the triangle of the other three
//! — tests 1 and 2 both true — is always class 1): the 14 cases of Table 1.
//!
//! **Case numbering.** `case = 2·idx + 1 + t4` for `idx = 4·t1 + 2·t2 + t3` in 0..=5 (cases
//! 1–12) and `case = 13, 14` for idx 6, 7 (class 1 only). This enumerates the 14 rows of
//! Table 1 by their test outcomes; the row order of the printed table is not reproduced.
//!
//! **Thickness (§3.5).** Class 2: the eye ray through the intersection point of the diagonals
//! meets edge v0'v1' at parameter α and edge v2'v3' at β; the thickness is the distance
//! between the two points. Class 1: the thick vertex is v1'; the line v0'v1' meets v2'v3' at
//! α ≥ 1 (the paper computes the depth there and scales it back by 1/α, gator.cg
//! `compute_depth`); equivalently the far point is on face v0'v2'v3' at parameter r = 1/α
//! along v0' → I. All other basis-graph vertices lie on the silhouette and have thickness 0.
//!
//! **Projected space.** `projected` are points in a space where eye rays are parallel to z:
//! normalised device coordinates (after the perspective divide) or orthographic view space.
//! A projective map keeps lines straight, so intersections and interpolation *in that space*
//! are exact; [`world_segment`] turns the two points back into world space with the vertices'
//! clip w (perspective-correct weights) to give the true length and scalars.
//!
//! **Degenerate projections.** Ties in tests 1–2 (a zero cross product: three vertices
//! collinear on screen, or two coincident) are broken as if the zero were positive, which
//! always puts one of two coincident vertices into slot v1' so the remaining diagonal is not a
//! point. Parameters are clamped to their edges (α, β ∈ [0, 1], r ∈ [0, 1]) and every division
//! guarded, so the thick vertex is always a convex combination of the tet's projected
//! vertices: no NaN, no triangle larger than the tet's projection.

/// The authors' MappingTable (gator.cg): for `idx = 4·t1 + 2·t2 + t3`, input vertex placed in
/// slot v0', v1', v2', v3'.
pub const MAPPING_TABLE: [[usize; 4]; 8] = [
    [0, 3, 1, 2],
    [0, 3, 2, 1],
    [0, 2, 1, 3],
    [0, 2, 3, 1],
    [0, 1, 3, 2],
    [0, 1, 2, 3],
    [2, 0, 3, 1],
    [3, 0, 2, 1],
];

/// Fan of the basis graph: node 0 is the thick vertex, nodes 1..=4 the rim
/// v2', v0', v3', then v1' (class 2) or v2' again (class 1: the fourth triangle degenerates).
/// wgpu has no fans, so each tet is drawn as these 4 triangles (12 vertices).
pub const FAN_TRIANGLES: [[usize; 3]; 4] = [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]];

/// Result of classifying one projected tetrahedron.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Classification {
    /// 1..=14: the row of Table 1 (see the module documentation for the numbering).
    pub case: u8,
    /// Test outcomes t1..t4 (t4: all four vertices on the hull).
    pub tests: [bool; 4],
    /// Shirley–Tuchman class of the projection: 1 (triangle + inner vertex) or 2 (quad).
    pub class: u8,
    /// Input vertex in slots v0', v1', v2', v3'.
    pub permutation: [usize; 4],
    /// Screen position (x, y of the projected space) of the thick vertex.
    pub thick_vertex: [f64; 2],
    /// |z_a − z_b| between the two points on the eye ray through the thick vertex, in the
    /// projected space's z units (the paper's thickness).
    pub thickness: f64,
    /// Affine weights (over the *input* vertices, in projected space) of the two points where
    /// the eye ray through the thick vertex enters and leaves the tet, in no particular order.
    pub point_a: [f64; 4],
    pub point_b: [f64; 4],
    /// Projected z of the two points (smaller is nearer the eye in wgpu's clip conventions).
    pub depth_a: f64,
    pub depth_b: f64,
}

impl Classification {
    /// The 5 nodes of the basis graph as input vertex indices, `None` for the thick vertex.
    pub fn basis_nodes(&self) -> [Option<usize>; 5] {
        let p = self.permutation;
        let last = if self.class == 2 { p[1] } else { p[2] };
        [None, Some(p[2]), Some(p[0]), Some(p[3]), Some(last)]
    }

    /// Screen positions of the 5 basis-graph nodes.
    pub fn basis_positions(&self, projected: &[[f64; 3]; 4]) -> [[f64; 2]; 5] {
        self.basis_nodes().map(|n| match n {
            None => self.thick_vertex,
            Some(i) => [projected[i][0], projected[i][1]],
        })
    }
}

fn cross2(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn sub2(a: [f64; 3], b: [f64; 3]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

/// Classifies a projected tetrahedron (the paper's four tests and Table 1) and finds its thick
/// vertex and thickness. `projected[i]` = (x, y, z) of vertex i in a space where eye rays are
/// parallel to z (see the module documentation). Same arithmetic as the vertex shader.
pub fn classify_cpu(projected: [[f64; 3]; 4]) -> Classification {
    classify_cpu_with(projected, &GeometricTests::PAPER)
}

/// The constants of the classifier's geometric tests. [`GeometricTests::PAPER`] is the paper's
/// (and the shader's); any other value exists so that a check of the classifier against
/// geometry (`tetbench reproduce gator`, claim G1) can be shown to fail on a classifier whose
/// geometric test is wrong while every label and truth-table outcome stays the same.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeometricTests {
    /// Test 4: the diagonals cross inside v0'v1' when α < this (the paper: 1, the end of the
    /// segment).
    pub test4_alpha_limit: f64,
}

impl GeometricTests {
    pub const PAPER: GeometricTests = GeometricTests {
        test4_alpha_limit: 1.0,
    };
}

/// [`classify_cpu`] with the geometric tests' constants given (see [`GeometricTests`]).
pub fn classify_cpu_with(projected: [[f64; 3]; 4], geometry: &GeometricTests) -> Classification {
    let p = projected;
    // Tests 1-3 (gator.cg tests123): z of three cross products about v0.
    let e1 = sub2(p[1], p[0]);
    let e2 = sub2(p[2], p[0]);
    let e3 = sub2(p[3], p[0]);
    let a = cross2(e1, e2);
    let b = cross2(e1, e3);
    let c = cross2(e3, e2);
    // "differ in sign", with a zero counted as positive (see Degenerate projections).
    let t1 = (a >= 0.0) != (b >= 0.0);
    let t2 = (a >= 0.0) != (c >= 0.0);
    let t3 = a >= 0.0;
    let idx = 4 * t1 as usize + 2 * t2 as usize + t3 as usize;
    let perm = MAPPING_TABLE[idx];
    let q = perm.map(|i| p[i]);

    // Intersection of v0'v1' with v2'v3' (gator.cg compute_intersection, Graphics Gems III):
    // 0 = C + α A − β B.
    let av = sub2(q[1], q[0]);
    let bv = sub2(q[3], q[2]);
    let cv = sub2(q[0], q[2]);
    let den = cross2(av, bv);
    let alpha_num = cross2(bv, cv);
    let beta_num = cross2(av, cv);

    // Test 4: α < 1 (class 2). Impossible for idx 6, 7 (v0 inside the triangle).
    let t4 = idx < 6 && den != 0.0 && {
        let alpha = alpha_num / den;
        alpha < geometry.test4_alpha_limit
    };
    let beta = if den != 0.0 {
        (beta_num / den).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut wa = [0.0; 4];
    let mut wb = [0.0; 4];
    if t4 {
        let alpha = (alpha_num / den).clamp(0.0, 1.0);
        wa[perm[0]] += 1.0 - alpha;
        wa[perm[1]] += alpha;
        wb[perm[2]] += 1.0 - beta;
        wb[perm[3]] += beta;
    } else {
        // Class 1: v1' is the thick vertex; the other point is on face v0'v2'v3' at
        // r = 1/α along v0' → I, I = v2' + β (v3' − v2').
        let r = if alpha_num != 0.0 {
            (den / alpha_num).clamp(0.0, 1.0)
        } else {
            0.0
        };
        wa[perm[1]] = 1.0;
        wb[perm[0]] += 1.0 - r;
        wb[perm[2]] += r * (1.0 - beta);
        wb[perm[3]] += r * beta;
    }
    let combine = |w: &[f64; 4], k: usize| (0..4).map(|i| w[i] * p[i][k]).sum::<f64>();
    let thick_vertex = if t4 {
        [combine(&wa, 0), combine(&wa, 1)]
    } else {
        [q[1][0], q[1][1]]
    };
    let (depth_a, depth_b) = (combine(&wa, 2), combine(&wb, 2));
    let thickness = (depth_a - depth_b).abs();
    let case = if idx < 6 {
        (2 * idx + 1 + t4 as usize) as u8
    } else {
        (13 + idx - 6) as u8
    };
    Classification {
        case,
        tests: [t1, t2, t3, t4],
        class: if t4 { 2 } else { 1 },
        permutation: perm,
        thick_vertex,
        thickness,
        point_a: wa,
        point_b: wb,
        depth_a,
        depth_b,
    }
}

/// The ray segment through the thick vertex in world space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThickSegment {
    /// World length of the segment (the thickness the optical model uses).
    pub length: f64,
    /// Scalar where the eye ray enters (nearer the eye) and leaves the tet.
    pub s_front: f64,
    pub s_back: f64,
}

/// Turns the projected-space weights of a classification into world points: a point with
/// projected weights λ has world weights λᵢ/wᵢ (normalised), `w` being the vertices' clip w
/// (1 for orthographic). Returns the world length and the scalars at both ends.
pub fn world_segment(
    c: &Classification,
    w: [f64; 4],
    world: [[f64; 3]; 4],
    scalars: [f64; 4],
) -> ThickSegment {
    let point = |lambda: &[f64; 4]| {
        let g: [f64; 4] = std::array::from_fn(|i| lambda[i] / w[i]);
        let sum: f64 = g.iter().sum();
        let g = g.map(|x| if sum > 0.0 { x / sum } else { 0.25 });
        let pos: [f64; 3] = std::array::from_fn(|k| (0..4).map(|i| g[i] * world[i][k]).sum());
        let s: f64 = (0..4).map(|i| g[i] * scalars[i]).sum();
        (pos, s)
    };
    let (pa, sa) = point(&c.point_a);
    let (pb, sb) = point(&c.point_b);
    let length =
        ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2) + (pa[2] - pb[2]).powi(2)).sqrt();
    let (s_front, s_back) = if c.depth_a <= c.depth_b {
        (sa, sb)
    } else {
        (sb, sa)
    };
    ThickSegment {
        length,
        s_front,
        s_back,
    }
}

/// Projects a tet with a camera the way the vertex shader does (in f64) and classifies it:
/// returns the projected points (NDC), the classification and the world segment.
pub fn classify_tet(
    camera: &render_core::Camera,
    world: [[f64; 3]; 4],
    scalars: [f64; 4],
) -> ([[f64; 3]; 4], Classification, ThickSegment) {
    let m = camera.view_proj();
    let mut w = [1.0; 4];
    let projected: [[f64; 3]; 4] = std::array::from_fn(|i| {
        let c = m * glam::DVec4::new(world[i][0], world[i][1], world[i][2], 1.0);
        w[i] = c.w;
        [c.x / c.w, c.y / c.w, c.z / c.w]
    });
    let cls = classify_cpu(projected);
    let seg = world_segment(&cls, w, world, scalars);
    (projected, cls, seg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn area2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
        cross2([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]])
    }

    /// Area of the convex hull of 4 points (gift wrapping on so few points is simplest).
    fn hull_area(p: &[[f64; 2]; 4]) -> f64 {
        // The hull of 4 points is the largest of the 4 triangles if one point is inside,
        // otherwise the quadrilateral = half the sum of the 4 triangle areas.
        let t = [
            area2(p[1], p[2], p[3]),
            area2(p[0], p[2], p[3]),
            area2(p[0], p[1], p[3]),
            area2(p[0], p[1], p[2]),
        ];
        let abs: Vec<f64> = t.iter().map(|x| x.abs()).collect();
        let max = abs.iter().cloned().fold(0.0, f64::max);
        let sum: f64 = abs.iter().sum();
        // Class 1: the largest triangle equals the sum of the other three.
        if (2.0 * max - sum).abs() <= 1e-9 * sum.max(1e-300) {
            max / 2.0
        } else {
            sum / 4.0
        }
    }

    /// Exact length of the line x = x0, y = y0 (parallel to z) inside the tet `p`.
    fn ray_length(p: &[[f64; 3]; 4], xy: [f64; 2]) -> f64 {
        // Barycentric coordinates are affine in z along the ray: λ(z) = λ0 + z λ1.
        let bary = |x: [f64; 3]| {
            let m = glam::DMat3::from_cols(
                glam::DVec3::from(p[1]) - glam::DVec3::from(p[0]),
                glam::DVec3::from(p[2]) - glam::DVec3::from(p[0]),
                glam::DVec3::from(p[3]) - glam::DVec3::from(p[0]),
            );
            let l = m.inverse() * (glam::DVec3::from(x) - glam::DVec3::from(p[0]));
            [1.0 - l.x - l.y - l.z, l.x, l.y, l.z]
        };
        let l0 = bary([xy[0], xy[1], 0.0]);
        let l1 = bary([xy[0], xy[1], 1.0]);
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for i in 0..4 {
            let d = l1[i] - l0[i];
            if d.abs() < 1e-12 {
                // Ray parallel to this face's plane (it runs along an edge or face when the
                // projection is degenerate): inside iff on the inner side, up to rounding.
                if l0[i] < -1e-12 {
                    return 0.0;
                }
                continue;
            }
            let z = -l0[i] / d;
            if d > 0.0 {
                lo = lo.max(z);
            } else {
                hi = hi.min(z);
            }
        }
        (hi - lo).max(0.0)
    }

    fn well_shaped(p: &[[f64; 3]; 4]) -> bool {
        let v = datasets::mesh::signed_volume6(*p).abs();
        let mut max_e: f64 = 0.0;
        for i in 0..4 {
            for j in i + 1..4 {
                let d = glam::DVec3::from(p[i]) - glam::DVec3::from(p[j]);
                max_e = max_e.max(d.length());
            }
        }
        v > 1e-3 * max_e.powi(3)
    }

    proptest! {
        /// The basis graph covers the projection exactly: the 4 fan triangles tile the convex
        /// hull (their areas sum to the hull's), and the thickness at the thick vertex is the
        /// tet's true extent along the eye ray there — the maximum over the projection.
        #[test]
        fn fan_tiles_hull_and_thickness_is_exact(coords in proptest::array::uniform12(-1.0f64..1.0)) {
            let p: [[f64; 3]; 4] = std::array::from_fn(|i| [coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]]);
            prop_assume!(well_shaped(&p));
            let c = classify_cpu(p);
            prop_assert!((1..=14).contains(&c.case));
            let pos = c.basis_positions(&p);
            let fan: f64 = FAN_TRIANGLES.iter().map(|t| area2(pos[t[0]], pos[t[1]], pos[t[2]]).abs() / 2.0).sum();
            let xy = p.map(|v| [v[0], v[1]]);
            let hull = hull_area(&xy);
            prop_assert!((fan - hull).abs() <= 1e-9 * hull.max(1e-12), "fan {fan} hull {hull} case {}", c.case);
            let exact = ray_length(&p, c.thick_vertex);
            prop_assert!((c.thickness - exact).abs() <= 1e-7 * exact.max(1e-3), "thickness {} exact {exact}", c.thickness);
            // Class 2 iff no vertex is inside the triangle of the other three.
            let inside = (0..4).any(|i| {
                let o: Vec<usize> = (0..4).filter(|&j| j != i).collect();
                let (a, b, cc) = (xy[o[0]], xy[o[1]], xy[o[2]]);
                let s = [area2(a, b, xy[i]), area2(b, cc, xy[i]), area2(cc, a, xy[i])];
                s.iter().all(|&x| x > 0.0) || s.iter().all(|&x| x < 0.0)
            });
            prop_assert_eq!(c.class == 1, inside);
        }
    }

    /// The 14 cases all occur, and each case fixes the tests' outcomes.
    #[test]
    fn all_fourteen_cases_occur() {
        let mut seen = [0usize; 15];
        let mut state = 0x2545F4914F6CDD1Du64;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..20000 {
            let p: [[f64; 3]; 4] = std::array::from_fn(|_| [rnd(), rnd(), rnd()]);
            let c = classify_cpu(p);
            seen[c.case as usize] += 1;
        }
        assert_eq!(seen[0], 0);
        for (case, &n) in seen.iter().enumerate().skip(1) {
            assert!(n > 0, "case {case} never occurred: {seen:?}");
        }
    }

    /// Degenerate projections: an edge along the eye ray (two coincident points), a face
    /// edge-on (a point on the segment of two others), all four collinear, all coincident.
    /// Results stay finite, the thick vertex inside the projection, thickness exact.
    #[test]
    fn degenerate_projections_are_finite_and_exact() {
        let base = [
            [0.0, 0.0, 0.1],
            [1.0, 0.0, 0.3],
            [0.2, 1.0, 0.5],
            [0.3, 0.3, 0.9],
        ];
        let mut cases = Vec::new();
        // Every pair of vertices made coincident on screen (an edge parallel to the ray).
        for i in 0..4 {
            for j in 0..4 {
                if i != j {
                    let mut p = base;
                    p[j][0] = p[i][0];
                    p[j][1] = p[i][1];
                    cases.push(p);
                }
            }
        }
        // Each vertex moved onto the segment between two others (a face seen edge-on).
        for i in 0..4 {
            let o: Vec<usize> = (0..4).filter(|&j| j != i).collect();
            let mut p = base;
            p[i][0] = 0.5 * (base[o[0]][0] + base[o[1]][0]);
            p[i][1] = 0.5 * (base[o[0]][1] + base[o[1]][1]);
            cases.push(p);
        }
        for p in &cases {
            let c = classify_cpu(*p);
            assert!(c.thick_vertex.iter().all(|v| v.is_finite()) && c.thickness.is_finite());
            let exact = ray_length(p, c.thick_vertex);
            assert!(
                (c.thickness - exact).abs() < 1e-9,
                "{p:?}: {} vs {exact}",
                c.thickness
            );
            let xy = p.map(|v| [v[0], v[1]]);
            let pos = c.basis_positions(p);
            let fan: f64 = FAN_TRIANGLES
                .iter()
                .map(|t| area2(pos[t[0]], pos[t[1]], pos[t[2]]).abs() / 2.0)
                .sum();
            assert!(
                (fan - hull_area(&xy)).abs() < 1e-9,
                "{p:?}: fan {fan} hull {}",
                hull_area(&xy)
            );
        }
        // Fully degenerate: zero-area projections give zero-area fans and finite numbers.
        let flat = [
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 0.5],
            [2.0, 2.0, 0.2],
            [0.5, 0.5, 1.0],
        ];
        let same = [
            [0.3, 0.3, 0.0],
            [0.3, 0.3, 0.5],
            [0.3, 0.3, 0.2],
            [0.3, 0.3, 1.0],
        ];
        for p in [flat, same] {
            let c = classify_cpu(p);
            assert!(c.thick_vertex.iter().all(|v| v.is_finite()) && c.thickness.is_finite());
            let pos = c.basis_positions(&p);
            let fan: f64 = FAN_TRIANGLES
                .iter()
                .map(|t| area2(pos[t[0]], pos[t[1]], pos[t[2]]).abs())
                .sum();
            assert!(fan < 1e-12);
            for k in 0..2 {
                let lo = p.iter().map(|v| v[k]).fold(f64::INFINITY, f64::min);
                let hi = p.iter().map(|v| v[k]).fold(f64::NEG_INFINITY, f64::max);
                assert!(c.thick_vertex[k] >= lo - 1e-12 && c.thick_vertex[k] <= hi + 1e-12);
            }
        }
    }

    /// Perspective: the world segment through the thick vertex is the true chord of the eye
    /// ray through the tet, and the scalars are the linear field's values at its ends.
    #[test]
    fn world_segment_matches_ray_through_tet() {
        use render_core::{Camera, Projection, Viewpoint};
        let world = [
            [0.0, 0.0, 0.0],
            [1.0, 0.1, 0.2],
            [0.2, 1.1, -0.1],
            [0.3, 0.2, 0.9],
        ];
        let scalars = [0.0, 1.0, 2.0, 3.0];
        let bounds = datasets::Aabb {
            min: [-1.0; 3],
            max: [2.0; 3],
        };
        for dir in [
            [0.3, 0.5, 1.0],
            [-1.0, 0.2, 0.1],
            [0.1, -1.0, 0.4],
            [0.7, 0.7, -0.7],
        ] {
            for proj in [Projection::default(), Projection::Orthographic] {
                let cam = Camera::fit(&bounds, &Viewpoint::new("t", dir), proj, 256, 256);
                let (ndc, cls, seg) = classify_tet(&cam, world, scalars);
                // Chord of the pixel ray through the thick vertex.
                let px = (cls.thick_vertex[0] + 1.0) * 0.5 * 256.0;
                let py = (1.0 - cls.thick_vertex[1]) * 0.5 * 256.0;
                let ray = cam.ray(px, py);
                let o = glam::DVec3::from(ray.origin);
                let d = glam::DVec3::from(ray.dir);
                let pts = world.map(glam::DVec3::from);
                let m = glam::DMat3::from_cols(pts[1] - pts[0], pts[2] - pts[0], pts[3] - pts[0])
                    .inverse();
                let b0 = m * (o - pts[0]);
                let b1 = m * d;
                let l0 = [1.0 - b0.x - b0.y - b0.z, b0.x, b0.y, b0.z];
                let l1 = [-b1.x - b1.y - b1.z, b1.x, b1.y, b1.z];
                let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
                for i in 0..4 {
                    let t = -l0[i] / l1[i];
                    if l1[i] > 0.0 {
                        lo = lo.max(t)
                    } else {
                        hi = hi.min(t)
                    }
                }
                assert!(
                    (seg.length - (hi - lo)).abs() < 1e-9,
                    "{dir:?} {proj:?}: {} vs {}",
                    seg.length,
                    hi - lo
                );
                let s_at = |t: f64| {
                    (0..4)
                        .map(|i| (l0[i] + t * l1[i]) * scalars[i])
                        .sum::<f64>()
                };
                assert!(
                    (seg.s_front - s_at(lo)).abs() < 1e-9 && (seg.s_back - s_at(hi)).abs() < 1e-9
                );
                assert!(ndc.iter().all(|p| p.iter().all(|v| v.is_finite())));
            }
        }
    }
}
