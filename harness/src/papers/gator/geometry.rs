//! Claim G1 from geometry, not from the classifier's own labels: for every tet of a mesh seen
//! from each viewpoint, the Shirley–Tuchman class follows from the convex hull of the four
//! projected vertices (three hull vertices: class 1, the fourth inside; four: class 2), and the
//! thick vertex is the inner vertex (class 1) or the point where the hull's two diagonals cross
//! (class 2), the place where the eye ray meets both the front and the back face (Wylie et al.
//! 2002, §3.2–3.3). Both are computed here by plain geometry, independently of the classifier's
//! four tests, and compared with what the classifier returns.
//!
//! A classifier whose geometric test is wrong can still produce every outcome of Table 1 with
//! the right case numbers (the truth-table check, G8, compares labels only); this check sees
//! it. Tets whose projection is too close to degenerate to call a class (three vertices nearly
//! collinear on screen, a vertex nearly on the hull's edge) are counted apart, not compared.

use gator_pt::Classification;
use rayon::prelude::*;
use render_core::{Camera, Viewpoint};

/// A tet is compared only if every orientation test of its projection is clear of zero by this
/// share of the product of the two edge lengths (the sine of the angle): nearer, f64 round-off
/// in the classifier and here could disagree.
const CLEAR_SINE: f64 = 1e-7;

/// The thick vertex must match within this share of the projection's longest edge.
const POSITION_TOLERANCE: f64 = 1e-6;

/// The check on one mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GeometryCheck {
    /// Plan name of the data set.
    pub dataset: String,
    pub viewpoints: usize,
    /// Projected tets compared (tets × viewpoints, less those skipped).
    pub compared: u64,
    /// Too close to degenerate to call (not compared).
    pub ambiguous: u64,
    /// With a vertex at or behind the eye (not drawn, not compared).
    pub behind_eye: u64,
    /// The classifier's class differs from the hull's.
    pub class_mismatches: u64,
    /// Same class, but the thick vertex is elsewhere.
    pub thick_vertex_mismatches: u64,
    /// A few mismatches in words (tet, viewpoint, what differs).
    pub examples: Vec<String>,
}

impl GeometryCheck {
    pub fn mismatches(&self) -> u64 {
        self.class_mismatches + self.thick_vertex_mismatches
    }
}

/// What geometry says of one projected tet: its class and thick vertex, or `None` when the
/// projection is too close to degenerate to call.
pub fn hull_class(p: &[[f64; 3]; 4]) -> Option<(u8, [f64; 2])> {
    let q: [[f64; 2]; 4] = p.map(|v| [v[0], v[1]]);
    // Orientation of (a, b, c), with whether it is clear of zero.
    let orient = |a: usize, b: usize, c: usize| -> Option<f64> {
        let (u, v) = (sub(q[b], q[a]), sub(q[c], q[a]));
        let cross = u[0] * v[1] - u[1] * v[0];
        let scale = len(u) * len(v);
        (scale > 0.0 && cross.abs() > CLEAR_SINE * scale).then_some(cross)
    };
    // Vertex i is inside the triangle of the other three when it lies on the same side of
    // each of the triangle's edges.
    let mut inside = vec![];
    for i in 0..4 {
        let o: Vec<usize> = (0..4).filter(|&j| j != i).collect();
        let (a, b, c) = (o[0], o[1], o[2]);
        let tri = orient(a, b, c)?;
        let s1 = orient(a, b, i)?;
        let s2 = orient(b, c, i)?;
        let s3 = orient(c, a, i)?;
        if [s1, s2, s3].iter().all(|s| s.signum() == tri.signum()) {
            inside.push(i);
        }
    }
    match inside[..] {
        [i] => Some((1, q[i])),
        [] => {
            // Four hull vertices: the diagonals are the one pairing whose segments cross.
            for (a, b, c, d) in [(0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2)] {
                let crosses = orient(a, b, c)?.signum() != orient(a, b, d)?.signum()
                    && orient(c, d, a)?.signum() != orient(c, d, b)?.signum();
                if crosses {
                    let (r, s) = (sub(q[b], q[a]), sub(q[d], q[c]));
                    let den = r[0] * s[1] - r[1] * s[0];
                    let w = sub(q[c], q[a]);
                    let t = (w[0] * s[1] - w[1] * s[0]) / den;
                    return Some((2, [q[a][0] + t * r[0], q[a][1] + t * r[1]]));
                }
            }
            None
        }
        _ => None,
    }
}

/// Projects a point into the classifier's space: normalised device coordinates after the
/// perspective divide (`None`: at or behind the eye).
fn project(m: &[[f64; 4]; 4], p: [f32; 3]) -> Option<[f64; 3]> {
    // Column-major: clip = Σ column_k · p_k (p_3 = 1).
    let v = [p[0] as f64, p[1] as f64, p[2] as f64, 1.0];
    let c: [f64; 4] = std::array::from_fn(|r| (0..4).map(|k| m[k][r] * v[k]).sum());
    (c[3] > 0.0).then(|| [c[0] / c[3], c[1] / c[3], c[2] / c[3]])
}

/// Checks `classify` against geometry on every tet of `mesh` from each viewpoint, at the
/// viewport `resolution` (square; only its aspect matters).
pub fn check_mesh(
    dataset: &str,
    mesh: &datasets::TetMesh,
    viewpoints: &[Viewpoint],
    resolution: u32,
    classify: &(dyn Fn([[f64; 3]; 4]) -> Classification + Sync),
) -> GeometryCheck {
    let mut out = GeometryCheck {
        dataset: dataset.to_string(),
        viewpoints: viewpoints.len(),
        ..Default::default()
    };
    for vp in viewpoints {
        let camera = Camera::fit(
            &mesh.bounds(),
            vp,
            Default::default(),
            resolution,
            resolution,
        );
        let m = camera.view_proj().to_cols_array_2d();
        let projected: Vec<Option<[f64; 3]>> =
            mesh.points.par_iter().map(|&p| project(&m, p)).collect();
        let part = mesh
            .tets
            .par_iter()
            .enumerate()
            .fold(GeometryCheck::default, |mut acc, (t, tet)| {
                let Some(p) = (|| {
                    Some([
                        projected[tet[0] as usize]?,
                        projected[tet[1] as usize]?,
                        projected[tet[2] as usize]?,
                        projected[tet[3] as usize]?,
                    ])
                })() else {
                    acc.behind_eye += 1;
                    return acc;
                };
                let Some((class, thick)) = hull_class(&p) else {
                    acc.ambiguous += 1;
                    return acc;
                };
                acc.compared += 1;
                let c = classify(p);
                let longest = (0..4)
                    .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
                    .map(|(i, j)| len(sub([p[i][0], p[i][1]], [p[j][0], p[j][1]])))
                    .fold(0.0, f64::max);
                if c.class != class {
                    acc.class_mismatches += 1;
                    if acc.examples.len() < 3 {
                        acc.examples.push(format!(
                            "tet {t} from {}: hull says class {class}, the classifier {} (case {})",
                            vp.name, c.class, c.case
                        ));
                    }
                } else if len(sub(c.thick_vertex, thick)) > POSITION_TOLERANCE * longest {
                    acc.thick_vertex_mismatches += 1;
                    if acc.examples.len() < 3 {
                        acc.examples.push(format!(
                            "tet {t} from {}: thick vertex at ({:.6}, {:.6}), the rays cross at ({:.6}, {:.6})",
                            vp.name, c.thick_vertex[0], c.thick_vertex[1], thick[0], thick[1]
                        ));
                    }
                }
                acc
            })
            .reduce(GeometryCheck::default, |mut a, b| {
                a.compared += b.compared;
                a.ambiguous += b.ambiguous;
                a.behind_eye += b.behind_eye;
                a.class_mismatches += b.class_mismatches;
                a.thick_vertex_mismatches += b.thick_vertex_mismatches;
                a.examples.extend(b.examples);
                a
            });
        out.compared += part.compared;
        out.ambiguous += part.ambiguous;
        out.behind_eye += part.behind_eye;
        out.class_mismatches += part.class_mismatches;
        out.thick_vertex_mismatches += part.thick_vertex_mismatches;
        out.examples.extend(part.examples);
    }
    out.examples.truncate(3);
    out
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn len(a: [f64; 2]) -> f64 {
    (a[0] * a[0] + a[1] * a[1]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hull_gives_the_class_and_the_thick_vertex() {
        // The fourth vertex inside the triangle: class 1, thick vertex there.
        let inner = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.2, 0.3, 1.0],
        ];
        assert_eq!(hull_class(&inner), Some((1, [0.2, 0.3])));
        // A convex quad: class 2, the diagonals 0-2 and 1-3 cross at the centre.
        let quad = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 1.0],
        ];
        assert_eq!(hull_class(&quad), Some((2, [0.5, 0.5])));
        // Collinear on screen: not called.
        let flat = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 1.0],
            [2.0, 0.0, 0.0],
            [0.0, 1.0, 1.0],
        ];
        assert_eq!(hull_class(&flat), None);
    }

    #[test]
    fn the_classifier_agrees_with_geometry_and_a_broken_test_4_does_not() {
        let mesh = datasets::registry::Registry::new(None)
            .resolve("box:2k", &datasets::LoadOptions::default())
            .expect("generated mesh")
            .mesh;
        let views = render_core::fixed_viewpoints();
        let ok = check_mesh("box:2k", &mesh, &views, 512, &gator_pt::classify_cpu);
        assert!(ok.compared > 10_000, "{ok:?}");
        assert_eq!(ok.mismatches(), 0, "{ok:?}");
        // Test 4 with the wrong threshold: the outcomes and labels stay those of Table 1, the
        // geometry does not.
        let broken = gator_pt::GeometricTests {
            test4_alpha_limit: 0.5,
        };
        let bad = check_mesh("box:2k", &mesh, &views, 512, &|p| {
            gator_pt::classify_cpu_with(p, &broken)
        });
        assert!(bad.class_mismatches > 0, "{bad:?}");
    }
}
