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
    /// Triangles of the tets' projections that hold a pixel centre well inside them (see
    /// [`covering_triangles`]): the triangles that must yield fragments, whatever the tie rule.
    pub covering_triangles: u64,
}

/// Pixel centres inside the projections of every tet of `mesh` (tets with a vertex at or
/// behind the eye count nothing: the shaders drop them or cannot project them).
pub fn projected_fragments(camera: &Camera, mesh: &datasets::TetMesh) -> u64 {
    projected_work(camera, mesh).fragments
}

/// [`projected_fragments`] and the tets that hold any of them.
pub fn projected_work(camera: &Camera, mesh: &datasets::TetMesh) -> ProjectedWork {
    let m = camera.view_proj_f32();
    let (w, h) = (camera.width as f64, camera.height as f64);
    // Pixel coordinates (x right, y down) of every vertex, None at or behind the eye.
    let screen: Vec<Option<[f64; 2]>> = mesh
        .points
        .par_iter()
        .map(|p| {
            let c: [f32; 4] =
                std::array::from_fn(|r| m[0][r] * p[0] + m[1][r] * p[1] + m[2][r] * p[2] + m[3][r]);
            (c[3] > 0.0).then(|| {
                let (x, y) = ((c[0] / c[3]) as f64, (c[1] / c[3]) as f64);
                [(x + 1.0) * 0.5 * w, (1.0 - y) * 0.5 * h]
            })
        })
        .collect();
    mesh.tets
        .par_iter()
        .map(|t| {
            let mut q = [[0.0; 2]; 4];
            for (k, &v) in t.iter().enumerate() {
                match screen[v as usize] {
                    Some(p) => q[k] = p,
                    None => return ProjectedWork::default(),
                }
            }
            let n = hull_pixels(&q, w, h);
            ProjectedWork {
                fragments: n,
                covering_tets: (n > 0) as u64,
                covering_triangles: if n > 0 {
                    covering_triangles(&q, w, h)
                } else {
                    0
                },
            }
        })
        .reduce(ProjectedWork::default, |a, b| ProjectedWork {
            fragments: a.fragments + b.fragments,
            covering_tets: a.covering_tets + b.covering_tets,
            covering_triangles: a.covering_triangles + b.covering_triangles,
        })
}

/// [`projected_work`] of the last view asked for: a renderer derives its counters once per
/// view, not once per frame.
#[derive(Debug, Default)]
pub struct FragmentsPerView {
    last: Option<(Camera, ProjectedWork)>,
}

impl FragmentsPerView {
    pub fn get(&mut self, camera: &Camera, mesh: &datasets::TetMesh) -> ProjectedWork {
        match &self.last {
            Some((c, w)) if c == camera => *w,
            _ => {
                let w = projected_work(camera, mesh);
                self.last = Some((camera.clone(), w));
                w
            }
        }
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

/// How far inside a triangle (in pixels) a centre must lie to count in [`covering_triangles`]:
/// a centre on or next to an edge goes to one of the two triangles by the rasteriser's tie rule
/// and its own f32 projection, which this count does not reproduce, so it is left out.
pub const EDGE_MARGIN_PX: f64 = 1e-3;

/// A fan triangle whose area is at most this times the square of its projection's larger
/// extent is not counted in [`covering_triangles`]: a renderer may classify the projection with
/// a tolerance and not draw it (the zero-area tests of the classifications here drop a face
/// of area up to 1e-5 of that square, or test signs exactly). Ten times the largest such
/// tolerance, so the count stays a lower bound.
pub const DEGENERATE_AREA_REL: f64 = 1e-4;

/// The triangles a projected tet is drawn as (Shirley and Tuchman's decomposition, which
/// GATOR's basis graph and fragment PT's fans both draw) that hold a pixel centre at least
/// [`EDGE_MARGIN_PX`] inside: a fan from the "thick" point over the edges of the projection's
/// hull, the thick point being the vertex inside the other three's triangle (3 triangles) or
/// else the crossing of the quadrilateral's diagonals (4 triangles). Centres near an edge are
/// not counted, so the count never exceeds the triangles that yield fragments; a degenerate
/// projection (a vertex on an edge, three in a line) counts the fan's non-degenerate part, and
/// triangles thinner than [`DEGENERATE_AREA_REL`] are left out.
pub fn covering_triangles(q: &[[f64; 2]; 4], w: f64, h: f64) -> u64 {
    let extent = |k: usize| {
        let (lo, hi) = q
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p[k]), hi.max(p[k]))
            });
        hi - lo
    };
    let min_area = DEGENERATE_AREA_REL * extent(0).max(extent(1)).powi(2);
    let fan = |thick: [f64; 2], ring: &[[f64; 2]]| -> u64 {
        (0..ring.len())
            .filter(|&i| {
                let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
                0.5 * cross(thick, a, b).abs() > min_area && has_inner_centre(thick, a, b, w, h)
            })
            .count() as u64
    };
    for i in 0..4 {
        let others: Vec<[f64; 2]> = (0..4).filter(|&k| k != i).map(|k| q[k]).collect();
        if in_triangle(q[i], others[0], others[1], others[2]) {
            return fan(q[i], &others);
        }
    }
    // No vertex inside the others' triangle: a quadrilateral whose diagonals cross.
    for (a, b, c, d) in [(0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2)] {
        if let Some(x) = crossing(q[a], q[b], q[c], q[d]) {
            // Diagonals a–b and c–d: the hull is a, c, b, d in order.
            return fan(x, &[q[a], q[c], q[b], q[d]]);
        }
    }
    0
}

fn cross(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

/// `p` inside the triangle or on its boundary (a triangle of any orientation).
fn in_triangle(p: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    let (d1, d2, d3) = (cross(a, b, p), cross(b, c, p), cross(c, a, p));
    let negative = d1 < 0.0 || d2 < 0.0 || d3 < 0.0;
    let positive = d1 > 0.0 || d2 > 0.0 || d3 > 0.0;
    !(negative && positive) && cross(a, b, c) != 0.0
}

/// Where segments a–b and c–d cross (each strictly between its ends), if they do.
fn crossing(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> Option<[f64; 2]> {
    let (c1, c2) = (cross(a, b, c), cross(a, b, d));
    let (c3, c4) = (cross(c, d, a), cross(c, d, b));
    if c1 * c2 < 0.0 && c3 * c4 < 0.0 {
        let t = c3 / (c3 - c4);
        Some([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])])
    } else {
        None
    }
}

/// Whether a pixel centre (k + ½, j + ½) of the `w`×`h` viewport lies at least
/// [`EDGE_MARGIN_PX`] inside triangle a, b, c: per row of centres, the x-interval each edge's
/// half-plane leaves.
fn has_inner_centre(a: [f64; 2], b: [f64; 2], c: [f64; 2], w: f64, h: f64) -> bool {
    let (a, b, c) = match cross(a, b, c) {
        s if s > 0.0 => (a, b, c),
        s if s < 0.0 => (a, c, b),
        _ => return false,
    };
    let edges = [(a, b), (b, c), (c, a)];
    let ymin = a[1].min(b[1]).min(c[1]);
    let ymax = a[1].max(b[1]).max(c[1]);
    let first_row = (ymin - 0.5).ceil().clamp(0.0, h) as u32;
    let end_row = (ymax - 0.5).ceil().clamp(0.0, h) as u32;
    (first_row..end_row).any(|j| {
        let y = j as f64 + 0.5;
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for (p, r) in edges {
            let (dx, dy) = (r[0] - p[0], r[1] - p[1]);
            // Inside: dx·(y − p.y) − dy·(x − p.x) > margin·|d|, a bound on x unless dy = 0.
            let rest = EDGE_MARGIN_PX * dx.hypot(dy) - dx * (y - p[1]);
            if dy == 0.0 {
                if rest >= 0.0 {
                    return false;
                }
            } else if dy < 0.0 {
                lo = lo.max(p[0] + rest / -dy);
            } else {
                hi = hi.min(p[0] - rest / dy);
            }
        }
        // The first centre right of lo, if it is left of hi and inside the viewport.
        let k = ((lo - 0.5).floor() + 1.0).max(0.0);
        k < w && k + 0.5 < hi
    })
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

    /// The fan's triangles that hold a centre: all of a large projection's, the one of three
    /// that holds a lone centre, and none where the only centre is on the fan's edges.
    #[test]
    fn covering_triangles_count_the_fan_triangles_with_centres() {
        // A triangle with its fourth vertex inside: a fan of three, each holding centres.
        let tri = [[0.0, 0.0], [16.0, 0.0], [0.0, 16.0], [4.0, 4.0]];
        assert_eq!(covering_triangles(&tri, 32.0, 32.0), 3);
        // The same with the inner vertex listed first: the same fan.
        let tri_first = [[4.0, 4.0], [0.0, 0.0], [16.0, 0.0], [0.0, 16.0]];
        assert_eq!(covering_triangles(&tri_first, 32.0, 32.0), 3);
        // A square, diagonals 0–2 and 1–3 crossing at (5, 5): four triangles.
        let square = [[1.0, 1.0], [9.0, 1.0], [9.0, 9.0], [1.0, 9.0]];
        assert_eq!(covering_triangles(&square, 32.0, 32.0), 4);
        // Outside the viewport, nothing; half inside, the two triangles there.
        assert_eq!(covering_triangles(&square, 0.5, 32.0), 0);
        let left_half = [[-9.0, 1.0], [-1.0, 1.0], [7.0, 9.0], [-9.0, 9.0]];
        assert!(covering_triangles(&left_half, 32.0, 32.0) < 4);
        // Inside one pixel around its centre (0.5, 0.5): one of the fan's three holds it.
        let pixel = [[0.2, 0.2], [0.95, 0.3], [0.3, 0.95], [0.4, 0.35]];
        assert_eq!(hull_pixels(&pixel, 4.0, 4.0), 1);
        assert_eq!(covering_triangles(&pixel, 4.0, 4.0), 1);
        // The unit pixel's square: its diagonals cross at the centre, which lies on all four
        // triangles' edges; the rasteriser gives it to one, this count to none (it is a lower
        // bound), while the hull holds it.
        let unit = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert_eq!(hull_pixels(&unit, 4.0, 4.0), 1);
        assert_eq!(covering_triangles(&unit, 4.0, 4.0), 0);
        // Flat: nothing.
        let flat = [[1.0, 2.0], [5.0, 2.0], [3.0, 2.0], [4.0, 2.0]];
        assert_eq!(covering_triangles(&flat, 16.0, 16.0), 0);
        // The inner vertex 0.003 pixel above the hull's lower edge: the sliver between them
        // holds the centre (8.5, 0.5) 0.0013 pixel inside, but its area is 9.4e-5 of the
        // extent's square, a face a renderer's zero test may drop: only the other two count.
        let sliver = [[0.0, 0.4985], [16.0, 0.4985], [8.0, 16.0], [8.0, 0.5015]];
        assert_eq!(covering_triangles(&sliver, 32.0, 32.0), 2);
        let (v, a, b) = (sliver[3], sliver[0], sliver[1]);
        assert!(has_inner_centre(v, a, b, 32.0, 32.0));
    }

    /// On random small tets, never more covering triangles than the fan has, nor than the
    /// hull has centres.
    #[test]
    fn covering_triangles_are_at_most_the_centres_and_the_fan() {
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut total = 0;
        for _ in 0..20_000 {
            let (cx, cy, size) = (next() * 16.0, next() * 16.0, next() * 6.0);
            let q: [[f64; 2]; 4] =
                std::array::from_fn(|_| [cx + next() * size, cy + next() * size]);
            let n = covering_triangles(&q, 16.0, 16.0);
            assert!(n <= 4 && n <= hull_pixels(&q, 16.0, 16.0), "{q:?}: {n}");
            total += n;
        }
        // Not vacuous: most of these tets hold centres (18,037 covering triangles here).
        assert!(total > 10_000, "{total}");
    }
}
