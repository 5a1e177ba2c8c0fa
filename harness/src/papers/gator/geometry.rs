//! Claim G1 from geometry, not from the classifier's own labels: for every tet of a mesh seen
//! from each viewpoint, the Shirley–Tuchman class follows from the convex hull of the four
//! projected vertices (three hull vertices: class 1, the fourth inside; four: class 2), and the
//! thick vertex is the inner vertex (class 1) or the point where the hull's two diagonals cross
//! (class 2), the place where the eye ray meets both the front and the back face (Wylie et al.
//! 2002, §3.2–3.3). Both are computed here by plain geometry, independently of the classifier's
//! four tests, and compared with what two classifiers return:
//!
//! - the shader's own (`gator.wgsl`, the copy that draws), read back per tet with the screen
//!   points it projected ([`gator_pt::GpuClassifier`]); its hull is taken from those points, so
//!   only the classifier's f32 arithmetic stands between it and the geometry;
//! - the CPU twin (`gator_pt::classify_cpu`, f64) on the f64 projection of the vertices.
//!
//! A classifier whose geometric test is wrong can still produce every outcome of Table 1 with
//! the right case numbers (the truth-table check, G8, compares labels only); this check sees
//! it. Tets whose projection is too close to degenerate to call a class (three vertices nearly
//! collinear on screen, a vertex nearly on the hull's edge) are counted apart, not compared;
//! the bar is the precision of each side's arithmetic.

use gator_pt::{Classification, GpuClassification};
use rayon::prelude::*;
use render_core::{Camera, Viewpoint};

/// The twin (f64) is compared only where every orientation test of the projection is clear of
/// zero by this share of the product of the two edge lengths (the sine of the angle): nearer,
/// f64 round-off in the classifier and here could disagree.
const CLEAR_SINE: f64 = 1e-7;

/// The twin's thick vertex must match within this share of the projection's longest edge.
const POSITION_TOLERANCE: f64 = 1e-6;

/// The shader's arithmetic is f32: a difference of two screen coordinates is exact or off by
/// one rounding and a 2D cross product adds about three more, so the sine it sees is off by
/// under 8·ε₃₂ (about 1e-6). The GPU is compared only where every orientation is clear of zero
/// by eight times that.
const CLEAR_SINE_F32: f64 = 64.0 * f32::EPSILON as f64;

/// The shader's thick vertex (class 2: where the diagonals cross, in f32) may be off by a few
/// roundings of the screen coordinates plus a few of the crossing's parameter, whose error
/// grows as one over the sine of the angle between the diagonals: this many ε₃₂ of
/// (largest |coordinate| + longest edge / smallest sine) is allowed.
const F32_ROUNDINGS: f64 = 32.0 * f32::EPSILON as f64;

/// What geometry says of one projected tet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hull {
    /// 1: a vertex inside the triangle of the other three; 2: four hull vertices.
    pub class: u8,
    /// The inner vertex, or where the diagonals cross.
    pub thick: [f64; 2],
    /// The smallest |sine| of the orientation tests behind it.
    pub min_sine: f64,
}

/// One classifier's comparison with the hull.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SideCheck {
    /// Projected tets compared.
    pub compared: u64,
    /// Too close to degenerate to call at this side's precision (not compared).
    pub ambiguous: u64,
    /// The classifier's class differs from the hull's.
    pub class_mismatches: u64,
    /// Same class, but the thick vertex is elsewhere.
    pub thick_vertex_mismatches: u64,
    /// A few mismatches in words (tet, viewpoint, what differs).
    pub examples: Vec<String>,
}

impl SideCheck {
    pub fn mismatches(&self) -> u64 {
        self.class_mismatches + self.thick_vertex_mismatches
    }

    fn add(&mut self, b: SideCheck) {
        self.compared += b.compared;
        self.ambiguous += b.ambiguous;
        self.class_mismatches += b.class_mismatches;
        self.thick_vertex_mismatches += b.thick_vertex_mismatches;
        self.examples.extend(b.examples);
        self.examples.truncate(3);
    }

    /// Compares a classifier's class and thick vertex with the hull, `tolerance` away at most.
    fn compare(&mut self, hull: &Hull, class: u8, thick: [f64; 2], tolerance: f64, what: String) {
        self.compared += 1;
        let wrong = if class != hull.class {
            self.class_mismatches += 1;
            format!("hull says class {}, the classifier {class}", hull.class)
        } else if len(sub(thick, hull.thick)) > tolerance {
            self.thick_vertex_mismatches += 1;
            format!(
                "thick vertex at ({:.6}, {:.6}), the rays cross at ({:.6}, {:.6})",
                thick[0], thick[1], hull.thick[0], hull.thick[1]
            )
        } else {
            return;
        };
        if self.examples.len() < 3 {
            self.examples.push(format!("{what}: {wrong}"));
        }
    }
}

/// The check on one mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct GeometryCheck {
    /// Plan name of the data set.
    pub dataset: String,
    pub viewpoints: usize,
    /// With a vertex at or behind the eye (not drawn, not compared).
    pub behind_eye: u64,
    /// The CPU twin against the hull of the f64 projection.
    pub twin: SideCheck,
    /// The shader's classifier against the hull of its own screen points (`Err`: not run,
    /// with why).
    pub gpu: Result<SideCheck, String>,
    /// Projected tets both sides could call where the shader's case differs from the twin's.
    pub gpu_twin_disagreements: u64,
}

impl GeometryCheck {
    fn new(dataset: &str, viewpoints: usize, gpu: Result<SideCheck, String>) -> GeometryCheck {
        GeometryCheck {
            dataset: dataset.to_string(),
            viewpoints,
            behind_eye: 0,
            twin: SideCheck::default(),
            gpu,
            gpu_twin_disagreements: 0,
        }
    }
}

/// What geometry says of one projected tet ([`Hull`]), or `None` when some orientation test
/// of the projection is within `clear_sine` of zero (too close to degenerate to call).
pub fn hull_class(p: &[[f64; 3]; 4], clear_sine: f64) -> Option<Hull> {
    let q: [[f64; 2]; 4] = p.map(|v| [v[0], v[1]]);
    let mut min_sine = f64::INFINITY;
    // Orientation of (a, b, c), if it is clear of zero.
    let mut orient = |a: usize, b: usize, c: usize| -> Option<f64> {
        let (u, v) = (sub(q[b], q[a]), sub(q[c], q[a]));
        let cross = u[0] * v[1] - u[1] * v[0];
        let scale = len(u) * len(v);
        let clear = scale > 0.0 && cross.abs() > clear_sine * scale;
        if clear {
            min_sine = min_sine.min(cross.abs() / scale);
        }
        clear.then_some(cross)
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
    let (class, thick) = match inside[..] {
        [i] => (1, q[i]),
        [] => {
            // Four hull vertices: the diagonals are the one pairing whose segments cross.
            let mut crossing = None;
            for (a, b, c, d) in [(0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2)] {
                let crosses = orient(a, b, c)?.signum() != orient(a, b, d)?.signum()
                    && orient(c, d, a)?.signum() != orient(c, d, b)?.signum();
                if crosses {
                    let (r, s) = (sub(q[b], q[a]), sub(q[d], q[c]));
                    let den = r[0] * s[1] - r[1] * s[0];
                    let w = sub(q[c], q[a]);
                    let t = (w[0] * s[1] - w[1] * s[0]) / den;
                    crossing = Some((
                        [q[a][0] + t * r[0], q[a][1] + t * r[1]],
                        den / (len(r) * len(s)),
                    ));
                    break;
                }
            }
            let (point, sine) = crossing?;
            min_sine = min_sine.min(sine.abs());
            (2, point)
        }
        _ => return None,
    };
    Some(Hull {
        class,
        thick,
        min_sine,
    })
}

/// Projects a point into the classifier's space: normalised device coordinates after the
/// perspective divide (`None`: at or behind the eye).
fn project(m: &[[f64; 4]; 4], p: [f32; 3]) -> Option<[f64; 3]> {
    // Column-major: clip = Σ column_k · p_k (p_3 = 1).
    let v = [p[0] as f64, p[1] as f64, p[2] as f64, 1.0];
    let c: [f64; 4] = std::array::from_fn(|r| (0..4).map(|k| m[k][r] * v[k]).sum());
    (c[3] > 0.0).then(|| [c[0] / c[3], c[1] / c[3], c[2] / c[3]])
}

/// The longest edge of a projection on screen, and its largest |coordinate|.
fn extent(p: &[[f64; 3]; 4]) -> (f64, f64) {
    let longest = (0..4)
        .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
        .map(|(i, j)| len(sub([p[i][0], p[i][1]], [p[j][0], p[j][1]])))
        .fold(0.0, f64::max);
    let largest = p
        .iter()
        .flat_map(|v| [v[0].abs(), v[1].abs()])
        .fold(0.0, f64::max);
    (longest, largest)
}

/// The shader's classification of every tet of the mesh from one camera, in mesh order.
pub type GpuReadback<'a> = dyn FnMut(&Camera) -> anyhow::Result<Vec<GpuClassification>> + 'a;

/// The two sides and their disagreements on one view.
#[derive(Default)]
struct ViewCheck {
    behind_eye: u64,
    twin: SideCheck,
    gpu: SideCheck,
    disagreements: u64,
}

/// Checks the CPU twin `classify` and, where given, the shader's classifier (`gpu`: its
/// readback per camera) against geometry on every tet of `mesh` from each viewpoint, at the
/// viewport `resolution` (square; only its aspect matters). A readback that fails, or that
/// does not hold one record per tet, leaves the GPU side `Err` with why.
pub fn check_mesh(
    dataset: &str,
    mesh: &datasets::TetMesh,
    viewpoints: &[Viewpoint],
    resolution: u32,
    classify: &(dyn Fn([[f64; 3]; 4]) -> Classification + Sync),
    mut gpu: Option<&mut GpuReadback>,
) -> GeometryCheck {
    let gpu_side = match gpu {
        Some(_) => Ok(SideCheck::default()),
        None => Err("the shader's classifier was not read back".into()),
    };
    let mut out = GeometryCheck::new(dataset, viewpoints.len(), gpu_side);
    for vp in viewpoints {
        let camera = Camera::fit(
            &mesh.bounds(),
            vp,
            Default::default(),
            resolution,
            resolution,
        );
        let readback = match (gpu.as_mut(), &out.gpu) {
            (Some(read), Ok(_)) => match read(&camera) {
                Ok(r) if r.len() == mesh.tets.len() => Some(r),
                Ok(r) => {
                    out.gpu = Err(format!(
                        "the shader's readback from {} holds {} records for {} tets",
                        vp.name,
                        r.len(),
                        mesh.tets.len()
                    ));
                    None
                }
                Err(e) => {
                    out.gpu = Err(format!(
                        "the shader's classification from {} could not be read back: {e:#}",
                        vp.name
                    ));
                    None
                }
            },
            _ => None,
        };
        let v = check_view(mesh, &camera, &vp.name, classify, readback.as_deref());
        out.behind_eye += v.behind_eye;
        out.twin.add(v.twin);
        if let (Ok(g), Some(_)) = (&mut out.gpu, &readback) {
            g.add(v.gpu);
            out.gpu_twin_disagreements += v.disagreements;
        }
    }
    out
}

/// The four projected vertices of `tet` (`None`: one is at or behind the eye).
fn corners(projected: &[Option<[f64; 3]>], tet: &[u32; 4]) -> Option<[[f64; 3]; 4]> {
    Some([
        projected[tet[0] as usize]?,
        projected[tet[1] as usize]?,
        projected[tet[2] as usize]?,
        projected[tet[3] as usize]?,
    ])
}

/// One view: every tet through the twin and, where read back, the shader's record.
fn check_view(
    mesh: &datasets::TetMesh,
    camera: &Camera,
    view: &str,
    classify: &(dyn Fn([[f64; 3]; 4]) -> Classification + Sync),
    gpu: Option<&[GpuClassification]>,
) -> ViewCheck {
    let m = camera.view_proj().to_cols_array_2d();
    let projected: Vec<Option<[f64; 3]>> =
        mesh.points.par_iter().map(|&p| project(&m, p)).collect();
    mesh.tets
        .par_iter()
        .enumerate()
        .fold(ViewCheck::default, |mut acc, (t, tet)| {
            let Some(p) = corners(&projected, tet) else {
                acc.behind_eye += 1;
                return acc;
            };
            let what = || format!("tet {t} from {view}");
            let twin = classify(p);
            let twin_hull = hull_class(&p, CLEAR_SINE);
            match &twin_hull {
                None => acc.twin.ambiguous += 1,
                Some(h) => {
                    let tolerance = POSITION_TOLERANCE * extent(&p).0;
                    acc.twin
                        .compare(h, twin.class, twin.thick_vertex, tolerance, what());
                }
            }
            let Some(g) = gpu.map(|g| &g[t]) else {
                return acc;
            };
            let q = g.screen_points();
            match hull_class(&q, CLEAR_SINE_F32) {
                None => acc.gpu.ambiguous += 1,
                Some(h) => {
                    let (longest, largest) = extent(&q);
                    let tolerance = F32_ROUNDINGS * (largest + longest / h.min_sine);
                    let thick = g.thick_vertex.map(f64::from);
                    acc.gpu.compare(&h, g.class as u8, thick, tolerance, what());
                    if twin_hull.is_some() && g.case != u32::from(twin.case) {
                        acc.disagreements += 1;
                    }
                }
            }
            acc
        })
        .reduce(ViewCheck::default, |mut a, b| {
            a.behind_eye += b.behind_eye;
            a.twin.add(b.twin);
            a.gpu.add(b.gpu);
            a.disagreements += b.disagreements;
            a
        })
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

    fn called(p: &[[f64; 3]; 4]) -> Option<(u8, [f64; 2])> {
        hull_class(p, CLEAR_SINE).map(|h| (h.class, h.thick))
    }

    #[test]
    fn the_hull_gives_the_class_and_the_thick_vertex() {
        // The fourth vertex inside the triangle: class 1, thick vertex there.
        let inner = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.2, 0.3, 1.0],
        ];
        assert_eq!(called(&inner), Some((1, [0.2, 0.3])));
        // A convex quad: class 2, the diagonals 0-2 and 1-3 cross at the centre, at right
        // angles.
        let quad = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 1.0],
        ];
        assert_eq!(called(&quad), Some((2, [0.5, 0.5])));
        let sine = hull_class(&quad, CLEAR_SINE).unwrap().min_sine;
        assert!((sine - 0.5f64.sqrt()).abs() < 1e-12, "{sine}");
        // Collinear on screen: not called.
        let flat = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 1.0],
            [2.0, 0.0, 0.0],
            [0.0, 1.0, 1.0],
        ];
        assert_eq!(called(&flat), None);
        // Nearly collinear (sine 1e-6): called in f64, too close to call at f32.
        let thin = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 1.0],
            [2.0, 2e-6, 0.0],
            [0.0, 1.0, 1.0],
        ];
        assert!(hull_class(&thin, CLEAR_SINE).is_some());
        assert!(hull_class(&thin, CLEAR_SINE_F32).is_none());
    }

    fn box2k() -> datasets::TetMesh {
        datasets::registry::Registry::new(None)
            .resolve("box:2k", &datasets::LoadOptions::default())
            .expect("generated mesh")
            .mesh
    }

    #[test]
    fn the_classifier_agrees_with_geometry_and_a_broken_test_4_does_not() {
        let mesh = box2k();
        let views = render_core::fixed_viewpoints();
        let ok = check_mesh("box:2k", &mesh, &views, 512, &gator_pt::classify_cpu, None);
        assert!(ok.twin.compared > 10_000, "{ok:?}");
        assert_eq!(ok.twin.mismatches(), 0, "{ok:?}");
        assert!(ok.gpu.is_err());
        // Test 4 with the wrong threshold: the outcomes and labels stay those of Table 1, the
        // geometry does not.
        let broken = gator_pt::GeometricTests {
            test4_alpha_limit: 0.5,
        };
        let bad = check_mesh(
            "box:2k",
            &mesh,
            &views,
            512,
            &|p| gator_pt::classify_cpu_with(p, &broken),
            None,
        );
        assert!(bad.twin.class_mismatches > 0, "{bad:?}");
    }

    /// The shader's classifier, read back from the device (lavapipe), agrees with the hull of
    /// its own screen points and with the twin; one record's class changed, or a record
    /// missing, is seen.
    #[test]
    fn the_shaders_classifier_agrees_with_geometry_and_a_changed_record_does_not() {
        let gpu = render_core::Gpu::new().expect("an adapter (lavapipe)");
        let mesh = box2k();
        // Four diagonal views (the axis views project a structured box's tets edge-on).
        let views = &render_core::fixed_viewpoints()[6..10];
        let mut classifier =
            gator_pt::GpuClassifier::new(&gpu, &mesh.points, &mesh.scalars, &mesh.tets, None)
                .unwrap();
        let mut read = |c: &Camera| classifier.classify(&gpu, c);
        let ok = check_mesh(
            "box:2k",
            &mesh,
            views,
            512,
            &gator_pt::classify_cpu,
            Some(&mut read),
        );
        let g = ok.gpu.clone().unwrap();
        assert!(g.compared > 7_500, "{ok:?}");
        assert!(
            g.ambiguous <= ok.twin.ambiguous + g.compared / 100,
            "{ok:?}"
        );
        assert_eq!(g.mismatches(), 0, "{ok:?}");
        assert_eq!(ok.gpu_twin_disagreements, 0, "{ok:?}");
        // Tet 0's class flipped in the first view's readback.
        let mut first = true;
        let mut corrupt = |c: &Camera| {
            let mut r = classifier.classify(&gpu, c)?;
            if std::mem::take(&mut first) {
                r[0].class = 3 - r[0].class;
            }
            Ok(r)
        };
        let bad = check_mesh(
            "box:2k",
            &mesh,
            views,
            512,
            &gator_pt::classify_cpu,
            Some(&mut corrupt),
        );
        let b = bad.gpu.unwrap();
        assert_eq!(b.class_mismatches, 1, "{b:?}");
        assert_eq!(bad.twin, ok.twin);
        // A readback short of one record: the GPU side is not judged, and says why.
        let mut short = |c: &Camera| {
            let mut r = classifier.classify(&gpu, c)?;
            r.pop();
            Ok(r)
        };
        let cut = check_mesh(
            "box:2k",
            &mesh,
            views,
            512,
            &gator_pt::classify_cpu,
            Some(&mut short),
        );
        assert!(cut.gpu.unwrap_err().contains("records for"));
    }
}
