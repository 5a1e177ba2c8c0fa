//! The fragments a projected-tetrahedra renderer rasterises, counted on the CPU: each tet's
//! triangles (GATOR's basis graph, fragment PT's fans) partition the convex hull of its four
//! projected vertices, so its fragments are the pixel centres inside that hull. The sum over
//! the mesh is the roofline's `fragments` work for those renderers, derived once per view and
//! outside the timed frame (a GPU count would cost an atomic per fragment, and occlusion
//! queries are only exact where the adapter offers precise ones).
//!
//! A pixel ray crosses exactly the tets whose hull holds its centre, so the sum equals the
//! ray caster's `ray_steps` without early termination, up to centres on a hull edge (where the
//! rasteriser's tie rule and f32 round-off decide); the ray caster's tests check that.

use rayon::prelude::*;

use crate::Camera;

/// The rasterisation work of a projected-tetrahedra frame, counted on the CPU.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ProjectedWork {
    /// Pixel centres inside the projections of all tets.
    pub fragments: u64,
    /// Tets whose projection holds at least one pixel centre: each draws at least one triangle
    /// that yields fragments, which costs the rasteriser more than a triangle that yields none
    /// (the roofline's `rasterisation` resource prices them apart; `covering_tets`).
    pub covering_tets: u64,
}

/// Pixel centres inside the projections of every tet of `mesh` (tets with a vertex at or
/// behind the eye count nothing: the shaders drop them or cannot project them).
pub fn projected_fragments(camera: &Camera, mesh: &datasets::TetMesh) -> u64 {
    projected_work(camera, mesh).fragments
}

/// [`projected_fragments`] and the tets that hold any of them.
pub fn projected_work(camera: &Camera, mesh: &datasets::TetMesh) -> ProjectedWork {
    let (w, h) = (camera.width as f64, camera.height as f64);
    let screen = screen_points(camera, mesh);
    mesh.tets
        .par_iter()
        .map(|t| {
            let mut q = [[0.0; 2]; 4];
            for (k, &v) in t.iter().enumerate() {
                match screen[v as usize] {
                    Some(p) => q[k] = p,
                    None => return 0,
                }
            }
            hull_pixels(&q, w, h)
        })
        .map(|n| ProjectedWork {
            fragments: n,
            covering_tets: (n > 0) as u64,
        })
        .reduce(ProjectedWork::default, |a, b| ProjectedWork {
            fragments: a.fragments + b.fragments,
            covering_tets: a.covering_tets + b.covering_tets,
        })
}

/// Pixel coordinates (x right, y down) of every vertex of `mesh`, None at or behind the eye,
/// with the shaders' f32 projection.
fn screen_points(camera: &Camera, mesh: &datasets::TetMesh) -> Vec<Option<[f64; 2]>> {
    let m = camera.view_proj_f32();
    let (w, h) = (camera.width as f64, camera.height as f64);
    mesh.points
        .par_iter()
        .map(|p| {
            let c: [f32; 4] =
                std::array::from_fn(|r| m[0][r] * p[0] + m[1][r] * p[1] + m[2][r] * p[2] + m[3][r]);
            (c[3] > 0.0).then(|| {
                let (x, y) = ((c[0] / c[3]) as f64, (c[1] / c[3]) as f64);
                [(x + 1.0) * 0.5 * w, (1.0 - y) * 0.5 * h]
            })
        })
        .collect()
}

/// The rasterisation work of drawing every face of a mesh once (HAVS draws its unique faces,
/// one triangle each), counted on the CPU.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FaceWork {
    /// Pixel centres inside the projections of all unique faces.
    pub fragments: u64,
    /// Unique faces whose projection holds at least one pixel centre: the triangles that yield
    /// fragments, each costing the rasteriser more than one that yields none
    /// (`covering_faces`; the roofline's `rasterisation` resource).
    pub covering_faces: u64,
}

/// [`FaceWork`] of the faces [`datasets::TetMesh::unique_faces`] lists (a face shared by two
/// tets once; faces with a vertex at or behind the eye count nothing).
pub fn face_work(camera: &Camera, mesh: &datasets::TetMesh) -> FaceWork {
    let (w, h) = (camera.width as f64, camera.height as f64);
    let screen = screen_points(camera, mesh);
    let adjacency = mesh.adjacency();
    mesh.tets
        .par_iter()
        .zip(adjacency)
        .enumerate()
        .map(|(t, (tet, neighbours))| {
            let mut work = FaceWork::default();
            for (f, &n) in neighbours.iter().enumerate() {
                // The owner's rule of `unique_faces`: a boundary face, or the lower tet's.
                if n != datasets::NO_NEIGHBOUR && (n as usize) < t {
                    continue;
                }
                let [a, b, c] = datasets::TET_FACES[f].map(|i| screen[tet[i] as usize]);
                let (Some(a), Some(b), Some(c)) = (a, b, c) else {
                    continue;
                };
                let n = hull_pixels(&[a, b, c, a], w, h);
                work.fragments += n;
                work.covering_faces += (n > 0) as u64;
            }
            work
        })
        .reduce(FaceWork::default, |a, b| FaceWork {
            fragments: a.fragments + b.fragments,
            covering_faces: a.covering_faces + b.covering_faces,
        })
}

/// A value derived from a view, kept for the last view asked for: a renderer derives its
/// counters once per view, not once per frame.
#[derive(Debug)]
pub struct PerView<T> {
    last: Option<(Camera, T)>,
}

impl<T> Default for PerView<T> {
    fn default() -> Self {
        PerView { last: None }
    }
}

impl<T: Copy> PerView<T> {
    /// The value for `camera`: the kept one, or `derive()`'s, then kept.
    pub fn get_or(&mut self, camera: &Camera, derive: impl FnOnce() -> T) -> T {
        match self.kept(camera) {
            Some(v) => v,
            None => {
                let v = derive();
                self.keep(camera, v);
                v
            }
        }
    }

    /// The kept value, if it was kept for `camera` (a value derived with the GPU, which a
    /// closure borrowing the renderer cannot derive inside [`PerView::get_or`]).
    pub fn kept(&self, camera: &Camera) -> Option<T> {
        match &self.last {
            Some((c, v)) if c == camera => Some(*v),
            _ => None,
        }
    }

    /// Keeps `v` as the value for `camera`.
    pub fn keep(&mut self, camera: &Camera, v: T) {
        self.last = Some((camera.clone(), v));
    }
}

/// [`projected_work`] of the last view asked for.
pub type FragmentsPerView = PerView<ProjectedWork>;

impl PerView<ProjectedWork> {
    pub fn get(&mut self, camera: &Camera, mesh: &datasets::TetMesh) -> ProjectedWork {
        self.get_or(camera, || projected_work(camera, mesh))
    }
}

/// Pixel centres (k + ½, j + ½), 0 ≤ k < w, 0 ≤ j < h, inside the convex hull of `q`: per
/// row, the hull's span is the extent of the row's crossings of the six segments between
/// the points; centres from its left end (included) to its right end (excluded).
pub fn hull_pixels(q: &[[f64; 2]; 4], w: f64, h: f64) -> u64 {
    let ymin = q.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    let ymax = q.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max);
    let first_row = (ymin - 0.5).ceil().clamp(0.0, h) as u32;
    let end_row = (ymax - 0.5).ceil().clamp(0.0, h) as u32;
    let mut n = 0u64;
    for j in first_row..end_row {
        let y = j as f64 + 0.5;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for a in 0..4 {
            for b in a + 1..4 {
                let (p, r) = (q[a], q[b]);
                let (y0, y1) = (p[1].min(r[1]), p[1].max(r[1]));
                if y < y0 || y > y1 {
                    continue;
                }
                // A horizontal segment on the row contributes both ends.
                let (x0, x1) = if r[1] == p[1] {
                    (p[0].min(r[0]), p[0].max(r[0]))
                } else {
                    let x = p[0] + (y - p[1]) / (r[1] - p[1]) * (r[0] - p[0]);
                    (x, x)
                };
                lo = lo.min(x0);
                hi = hi.max(x1);
            }
        }
        if lo <= hi {
            let first = (lo - 0.5).ceil().clamp(0.0, w);
            let end = (hi - 0.5).ceil().clamp(0.0, w);
            n += (end - first).max(0.0) as u64;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hull_holds_the_centres_inside_it() {
        // The square [1, 5) × [1, 5) as four corners: 4 × 4 centres.
        let square = [[1.0, 1.0], [5.0, 1.0], [5.0, 5.0], [1.0, 5.0]];
        assert_eq!(hull_pixels(&square, 16.0, 16.0), 16);
        // A triangle with the fourth point inside it: the triangle's centres. Row y = j + ½
        // spans [0, 7.5 − j), so it holds the centres k + ½ with k < 7 − j.
        let tri = [[0.0, 0.0], [8.0, 0.0], [0.0, 8.0], [1.0, 1.0]];
        assert_eq!(
            hull_pixels(&tri, 16.0, 16.0),
            (0..8u64).map(|j| 7 - j).sum::<u64>()
        );
        // Clipped to the viewport.
        let big = [[-10.0, -10.0], [30.0, -10.0], [30.0, 30.0], [-10.0, 30.0]];
        assert_eq!(hull_pixels(&big, 16.0, 8.0), 128);
        // A degenerate (flat) tet covers nothing.
        let flat = [[1.0, 2.0], [5.0, 2.0], [3.0, 2.0], [4.0, 2.0]];
        assert_eq!(hull_pixels(&flat, 16.0, 16.0), 0);
    }

    /// A tet counts as covering when its projection holds a pixel centre; a second tet far
    /// smaller than a pixel adds none.
    #[test]
    fn covering_tets_count_the_tets_with_fragments() {
        let points = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.5, 0.5, 0.5],
            [0.5001, 0.5, 0.5],
            [0.5, 0.5001, 0.5],
            [0.5, 0.5, 0.5001],
        ];
        let one = |tets: Vec<[u32; 4]>| {
            let n = points.len();
            let mesh = datasets::TetMesh::new(
                "two",
                points.iter().map(|p| p.map(|c| c as f32)).collect(),
                vec![0.0; n],
                "s",
                tets,
            )
            .unwrap();
            let vp = crate::Viewpoint::new("+z", [0.0, 0.0, 1.0]);
            let cam = Camera::fit(&mesh.bounds(), &vp, crate::Projection::Orthographic, 64, 64);
            projected_work(&cam, &mesh)
        };
        let big = one(vec![[0, 1, 2, 3]]);
        assert_eq!(big.covering_tets, 1);
        assert!(big.fragments > 100, "{big:?}");
        let both = one(vec![[0, 1, 2, 3], [4, 5, 6, 7]]);
        assert_eq!(both.covering_tets, 1, "{both:?}");
        assert!(both.fragments <= big.fragments + 1, "{both:?}");
    }

    /// Two tets sharing a face: seven unique faces, the shared one counted once. Seen along
    /// +z, faces that stand edge-on cover nothing, and the faces' fragments are the tets' hull
    /// fragments counted once per face that lies over them (a pixel ray through a convex tet
    /// crosses two of its faces).
    #[test]
    fn covering_faces_count_each_unique_face_once() {
        let points: Vec<[f32; 3]> = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.2, 0.3, 1.0],
            [0.3, 0.2, -1.0],
        ];
        let mesh = |tets: Vec<[u32; 4]>| {
            datasets::TetMesh::new("pair", points.clone(), vec![0.0; points.len()], "s", tets)
                .unwrap()
        };
        let vp = crate::Viewpoint::new("+z", [0.0, 0.0, 1.0]);
        let one = mesh(vec![[0, 1, 2, 3]]);
        let cam = Camera::fit(&one.bounds(), &vp, crate::Projection::Orthographic, 64, 64);
        let w1 = face_work(&cam, &one);
        // Seen from +z the apex projects inside the base: all four faces hold centres, and
        // every centre of the base's triangle lies under exactly two of them, up to centres on
        // the side faces' shared edges, where each face's own f64 crossing decides (one here).
        assert_eq!(w1.covering_faces, 4, "{w1:?}");
        let hull = projected_work(&cam, &one).fragments;
        assert!(hull > 500, "{hull}");
        assert!(
            w1.fragments.abs_diff(2 * hull) <= 3,
            "{w1:?} against 2 × {hull}"
        );
        let pair = mesh(vec![[0, 1, 2, 3], [0, 2, 1, 4]]);
        let cam = Camera::fit(&pair.bounds(), &vp, crate::Projection::Orthographic, 64, 64);
        let w2 = face_work(&cam, &pair);
        assert_eq!(pair.unique_faces().faces.len(), 7);
        assert_eq!(w2.covering_faces, 7, "{w2:?}");
        // From +x, points 0 and 1 project onto one point: the base and the two side faces
        // through edge 0–1 stand edge-on and cover nothing.
        let side = crate::Viewpoint::new("+x", [1.0, 0.0, 0.0]);
        let cam = Camera::fit(
            &pair.bounds(),
            &side,
            crate::Projection::Orthographic,
            64,
            64,
        );
        let w3 = face_work(&cam, &pair);
        assert_eq!(w3.covering_faces, 4, "{w3:?}");
    }
}
