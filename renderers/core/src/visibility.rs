//! Visibility orders shared by the cell-projection algorithms (GATOR-style PT, fragment PT, …):
//! tet ids back to front, farthest first, so that drawing them in order with "over" blending
//! composites correctly.
//!
//! - **Centroid orders** sort the tets by [`Camera::sort_distance`] of their centroids: the LSD
//!   radix sort (HAVS §5.1; the default), a bucket sort into depth slabs (Marroquim et al. 2006
//!   §4, used while the camera moves: within a slab the order is left as is), and a merge sort
//!   (Marroquim et al. 2006 §4, for still frames). Centroid order is only approximate: two
//!   adjacent tets can be ordered wrongly across their shared face.
//! - **MPVONC** (Williams 1992, "Visibility ordering meshed polyhedra", ACM TOG 11(2)) is exact
//!   for acyclic convex meshes: every interior face defines a "behind" relation between its two
//!   tets (the tet on the far side of the face plane, seen from the eye, is behind the other);
//!   a depth-first topological sort of that relation, emitting a tet after every tet behind it
//!   (post-order), gives a valid back-to-front order. Phase I (adjacency, face planes) is done
//!   once per mesh and cached; Phases II (the relation) and III (the sort) run per view.
//!
//! **Non-convex meshes** (Williams's "NC" extension). Across a concavity two tets can occlude
//! each other with no shared face, so the face relation alone is incomplete. As in MPVONC, the
//! depth-first search is started from the *entry cells*, the tets owning a boundary face that
//! faces the eye (where view rays enter the mesh), taken in order of decreasing distance of that
//! boundary face's centroid from the eye, farthest first: whatever lies behind a far entry face
//! is emitted before the parts of the mesh nearer to the eye. This is Williams's heuristic, not
//! an exact order for every non-convex mesh (XMPVO, Silva et al. 1998, is exact); across
//! interior faces the order stays exact.
//!
//! **Cycles.** The behind relation can have cycles (possible with perspective, or with
//! degenerate and badly shaped cells). A back edge of the depth-first search, which closes a
//! cycle, is ignored: deterministic, since the search order is fixed by the entry-face order and
//! the face order of each tet. The count is returned in [`SortStats::cycle_breaks`].

use std::fmt;
use std::str::FromStr;
use std::time::Instant;

use datasets::{TetMesh, NO_NEIGHBOUR, TET_FACES};
use glam::DVec3;
use rayon::prelude::*;

use crate::scene::Camera;
use crate::sort::{
    bucket_sort_indices, merge_sort_indices, radix_sort_indices_descending, RadixScratch,
    DEFAULT_SLABS,
};

/// Which visibility order a renderer uses; goes into the `sort=` setting of result rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum VisibilityOrder {
    /// Centroid distance, LSD radix sort (HAVS §5.1).
    #[default]
    CentroidRadix,
    /// Centroid distance, bucket sort into `slabs` depth slabs (Marroquim et al. 2006 §4).
    CentroidBucket { slabs: usize },
    /// Centroid distance, stable merge sort (Marroquim et al. 2006 §4, still frames).
    CentroidMerge,
    /// Williams's MPVONC over the face adjacency (exact on acyclic convex meshes).
    Mpvonc,
}

impl VisibilityOrder {
    /// Every order, with the default slab count for the bucket sort.
    pub const ALL: [VisibilityOrder; 4] = [
        VisibilityOrder::CentroidRadix,
        VisibilityOrder::CentroidBucket {
            slabs: DEFAULT_SLABS,
        },
        VisibilityOrder::CentroidMerge,
        VisibilityOrder::Mpvonc,
    ];

    /// Whether the order is exact across interior faces (on acyclic meshes).
    pub fn is_exact(self) -> bool {
        self == VisibilityOrder::Mpvonc
    }
}

impl fmt::Display for VisibilityOrder {
    /// `radix`, `bucket` (20 slabs) or `bucket:N`, `merge`, `mpvonc`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            VisibilityOrder::CentroidRadix => f.write_str("radix"),
            VisibilityOrder::CentroidBucket { slabs } if slabs == DEFAULT_SLABS => {
                f.write_str("bucket")
            }
            VisibilityOrder::CentroidBucket { slabs } => write!(f, "bucket:{slabs}"),
            VisibilityOrder::CentroidMerge => f.write_str("merge"),
            VisibilityOrder::Mpvonc => f.write_str("mpvonc"),
        }
    }
}

/// A visibility order name that is not one of `radix`, `bucket[:N]`, `merge`, `mpvonc`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown visibility order `{0}` (expected radix, bucket, bucket:N with N ≥ 1, merge or mpvonc)"
)]
pub struct ParseOrderError(pub String);

impl FromStr for VisibilityOrder {
    type Err = ParseOrderError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim().to_ascii_lowercase();
        match t.as_str() {
            "radix" => Ok(VisibilityOrder::CentroidRadix),
            "bucket" => Ok(VisibilityOrder::CentroidBucket {
                slabs: DEFAULT_SLABS,
            }),
            "merge" => Ok(VisibilityOrder::CentroidMerge),
            "mpvonc" => Ok(VisibilityOrder::Mpvonc),
            _ => match t.strip_prefix("bucket:").map(str::parse::<usize>) {
                Some(Ok(slabs)) if slabs >= 1 => Ok(VisibilityOrder::CentroidBucket { slabs }),
                _ => Err(ParseOrderError(s.to_string())),
            },
        }
    }
}

/// What one [`VisibilitySorter::back_to_front`] call did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SortStats {
    pub order: VisibilityOrder,
    /// Tets ordered.
    pub cells: usize,
    /// CPU ms of the per-view work (keys and sort, or MPVONC phases II and III).
    pub cpu_ms: f64,
    /// CPU ms of the once-per-mesh precomputation done during this call (0 when cached).
    pub precompute_ms: f64,
    /// MPVONC: behind-relation edges ignored because they closed a cycle.
    pub cycle_breaks: usize,
    /// MPVONC: depth-first roots, i.e. boundary faces facing the eye.
    pub entry_faces: usize,
    /// MPVONC: interior faces seen edge-on (the eye in their plane), which order nothing.
    pub edge_on_faces: usize,
    /// MPVONC: tets not reached from any entry face (cycles, or the eye inside the mesh),
    /// searched from afterwards in decreasing centroid distance.
    pub unreached: usize,
}

/// An interior face between `tets[0]` and `tets[1]`; the plane `n·x = d` has its unit normal
/// pointing out of `tets[0]` (into `tets[1]`).
#[derive(Debug, Clone, Copy)]
struct InteriorFace {
    plane: [f64; 4],
}

/// A boundary face facing out of the mesh, with its centroid.
#[derive(Debug, Clone, Copy)]
struct EntryCandidate {
    plane: [f64; 4],
    centroid: [f64; 3],
    tet: u32,
}

/// MPVONC phase I: what does not depend on the camera.
struct FaceGraph {
    interior: Vec<InteriorFace>,
    /// Per tet and local face: the interior face id, with [`SECOND`] set when the tet is the
    /// face's `tets[1]`, or [`BOUNDARY`].
    tet_faces: Vec<[u32; 4]>,
    boundary: Vec<EntryCandidate>,
    /// Distances below this (a millionth of a millionth of the mesh size) count as "in the
    /// plane": such a face orders nothing.
    edge_on_tolerance: f64,
}

const SECOND: u32 = 1 << 31;
const BOUNDARY: u32 = u32::MAX;

fn plane_of(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 4] {
    let (a, b, c) = (DVec3::from(a), DVec3::from(b), DVec3::from(c));
    let n = (b - a).cross(c - a);
    let n = n / n.length().max(f64::MIN_POSITIVE);
    [n.x, n.y, n.z, n.dot(a)]
}

impl FaceGraph {
    fn build(mesh: &TetMesh) -> FaceGraph {
        let adj = mesh.adjacency();
        let mut tet_faces = vec![[BOUNDARY; 4]; mesh.num_tets()];
        let mut interior = Vec::with_capacity(mesh.num_tets() * 2);
        let mut boundary = Vec::new();
        let point = |v: u32| mesh.points[v as usize].map(|c| c as f64);
        for (t, a) in adj.iter().enumerate() {
            for (f, &nb) in a.iter().enumerate() {
                let [i, j, k] = TET_FACES[f].map(|l| point(mesh.tets[t][l]));
                if nb == NO_NEIGHBOUR {
                    let centroid = [0, 1, 2].map(|x| (i[x] + j[x] + k[x]) / 3.0);
                    boundary.push(EntryCandidate {
                        plane: plane_of(i, j, k),
                        centroid,
                        tet: t as u32,
                    });
                } else if (nb as usize) > t {
                    let id = interior.len() as u32;
                    interior.push(InteriorFace {
                        plane: plane_of(i, j, k),
                    });
                    tet_faces[t][f] = id;
                    // The neighbour's local index of the shared face.
                    let g = adj[nb as usize]
                        .iter()
                        .position(|&x| x as usize == t)
                        .expect("adjacency is symmetric");
                    tet_faces[nb as usize][g] = id | SECOND;
                }
            }
        }
        FaceGraph {
            interior,
            tet_faces,
            boundary,
            edge_on_tolerance: 1e-12 * mesh.bounds().diagonal().max(1e-300),
        }
    }
}

/// Signed distance of the eye from `plane`, in the direction of its normal: positive when the
/// eye is on the side the normal points to. Orthographic cameras have their eye at infinity
/// against the view direction, so only the direction counts.
#[inline]
fn eye_side(plane: &[f64; 4], eye: &Eye) -> f64 {
    let n = DVec3::new(plane[0], plane[1], plane[2]);
    match eye {
        Eye::Point(e) => n.dot(*e) - plane[3],
        Eye::Direction(back) => n.dot(*back),
    }
}

enum Eye {
    Point(DVec3),
    /// Unit vector from the scene towards the eye at infinity.
    Direction(DVec3),
}

impl Eye {
    fn of(camera: &Camera) -> Eye {
        if camera.is_perspective() {
            Eye::Point(DVec3::from(camera.eye))
        } else {
            Eye::Direction(-DVec3::from(camera.forward()))
        }
    }
}

/// Per-mesh data, computed once and cached by the mesh's content hash.
struct MeshCache {
    hash: String,
    /// In f32, like the points they average and the keys made of them: f64 would add 12 B per
    /// tet (240 MB at 20 M tets) for digits the f32 sort keys drop.
    centroids: Vec<[f32; 3]>,
    graph: Option<FaceGraph>,
}

/// Produces back-to-front tet orders frame after frame, keeping its scratch and the per-mesh
/// precomputation (centroids; MPVONC's face planes) between calls.
#[derive(Default)]
pub struct VisibilitySorter {
    order: VisibilityOrder,
    cache: Option<MeshCache>,
    keys: Vec<f32>,
    radix: RadixScratch,
    merge: Vec<u64>,
    behind: Vec<u8>,
    state: Vec<u8>,
    stack: Vec<(u32, u8)>,
    entry_keys: Vec<f32>,
    entry_order: Vec<u32>,
}

impl VisibilitySorter {
    pub fn new(order: VisibilityOrder) -> VisibilitySorter {
        VisibilitySorter {
            order,
            ..Default::default()
        }
    }

    pub fn order(&self) -> VisibilityOrder {
        self.order
    }

    pub fn set_order(&mut self, order: VisibilityOrder) {
        self.order = order;
    }

    /// Writes the ids of all tets of `mesh` into `out`, back to front (farthest first) as seen
    /// by `camera`, with the sorter's order.
    pub fn back_to_front(
        &mut self,
        mesh: &TetMesh,
        camera: &Camera,
        out: &mut Vec<u32>,
    ) -> SortStats {
        let pre = Instant::now();
        let mut precompute_ms = 0.0;
        if self
            .cache
            .as_ref()
            .is_none_or(|c| c.hash != mesh.content_hash() || c.centroids.len() != mesh.num_tets())
        {
            let centroids = (0..mesh.num_tets())
                .into_par_iter()
                .map(|t| {
                    let p = mesh.tet_points(t);
                    [0, 1, 2].map(|a| (0.25 * (p[0][a] + p[1][a] + p[2][a] + p[3][a])) as f32)
                })
                .collect();
            self.cache = Some(MeshCache {
                hash: mesh.content_hash().to_string(),
                centroids,
                graph: None,
            });
            precompute_ms = pre.elapsed().as_secs_f64() * 1e3;
        }
        if self.order == VisibilityOrder::Mpvonc
            && self.cache.as_ref().is_some_and(|c| c.graph.is_none())
        {
            let t = Instant::now();
            let graph = FaceGraph::build(mesh);
            self.cache.as_mut().expect("cache built above").graph = Some(graph);
            precompute_ms += t.elapsed().as_secs_f64() * 1e3;
        }
        let start = Instant::now();
        let mut stats = SortStats {
            order: self.order,
            cells: mesh.num_tets(),
            precompute_ms,
            ..Default::default()
        };
        match self.order {
            VisibilityOrder::CentroidRadix => {
                self.centroid_keys(camera);
                radix_sort_indices_descending(&self.keys, out, &mut self.radix);
            }
            VisibilityOrder::CentroidBucket { slabs } => {
                self.centroid_keys(camera);
                bucket_sort_indices(&self.keys, slabs, true, out);
            }
            VisibilityOrder::CentroidMerge => {
                self.centroid_keys(camera);
                merge_sort_indices(&self.keys, true, out, &mut self.merge);
            }
            VisibilityOrder::Mpvonc => self.mpvonc(mesh, camera, out, &mut stats),
        }
        stats.cpu_ms = start.elapsed().as_secs_f64() * 1e3;
        stats
    }

    /// Centroid sort keys: [`Camera::sort_distance`] (distance from the eye in perspective, depth
    /// along the view axis in orthographic projection).
    fn centroid_keys(&mut self, camera: &Camera) {
        let centroids = &self.cache.as_ref().expect("cache built").centroids;
        self.keys.clear();
        self.keys.par_extend(
            centroids
                .par_iter()
                .map(|&c| camera.sort_distance(c.map(f64::from)) as f32),
        );
    }

    fn mpvonc(
        &mut self,
        mesh: &TetMesh,
        camera: &Camera,
        out: &mut Vec<u32>,
        stats: &mut SortStats,
    ) {
        let cache = self.cache.as_ref().expect("cache built");
        let graph = cache.graph.as_ref().expect("graph built");
        let eye = Eye::of(camera);
        let tol = graph.edge_on_tolerance;
        let n = mesh.num_tets();
        let adj = mesh.adjacency();

        // Phase II: behind[t] bit f is set when the tet across face f is behind t (must be drawn
        // before t). Both tets of a face evaluate the same f64 plane, so they always agree.
        self.behind.clear();
        self.behind
            .par_extend(graph.tet_faces.par_iter().map(|faces| {
                let mut bits = 0u8;
                for (f, &id) in faces.iter().enumerate() {
                    if id == BOUNDARY {
                        continue;
                    }
                    let s = eye_side(&graph.interior[(id & !SECOND) as usize].plane, &eye);
                    // s > 0: the eye is on the side of tets[1] (the normal points out of tets[0]),
                    // so tets[0] is behind tets[1].
                    let neighbour_behind = if id & SECOND != 0 { s > tol } else { s < -tol };
                    if neighbour_behind {
                        bits |= 1 << f;
                    }
                }
                bits
            }));
        stats.edge_on_faces = graph
            .interior
            .par_iter()
            .filter(|face| eye_side(&face.plane, &eye).abs() <= tol)
            .count();

        // Entry faces (boundary faces whose outside the eye is on), farthest first.
        let entries: Vec<&EntryCandidate> = graph
            .boundary
            .iter()
            .filter(|b| eye_side(&b.plane, &eye) > tol)
            .collect();
        stats.entry_faces = entries.len();
        self.entry_keys.clear();
        self.entry_keys.extend(
            entries
                .iter()
                .map(|b| camera.sort_distance(b.centroid) as f32),
        );
        radix_sort_indices_descending(&self.entry_keys, &mut self.entry_order, &mut self.radix);

        // Phase III: depth-first search along "behind", emitting each tet after everything
        // behind it (post-order). state: 0 unvisited, 1 on the stack, 2 emitted.
        out.clear();
        out.reserve(n);
        self.state.clear();
        self.state.resize(n, 0);
        let mut search = Search {
            state: &mut self.state,
            stack: &mut self.stack,
            behind: &self.behind,
            adj,
            cycle_breaks: 0,
        };
        for &e in &self.entry_order {
            search.run(entries[e as usize].tet, out);
        }
        // Tets no entry face reaches (only in cycles, or with the eye inside the mesh): search
        // from them in decreasing centroid distance, so the fallback is still roughly ordered.
        if out.len() < n {
            let remaining: Vec<u32> = (0..n as u32)
                .filter(|&t| search.state[t as usize] == 0)
                .collect();
            stats.unreached = remaining.len();
            let keys: Vec<f32> = remaining
                .iter()
                .map(|&t| camera.sort_distance(cache.centroids[t as usize].map(f64::from)) as f32)
                .collect();
            let mut order = Vec::new();
            radix_sort_indices_descending(&keys, &mut order, &mut RadixScratch::default());
            for &i in &order {
                search.run(remaining[i as usize], out);
            }
        }
        let cycle_breaks = search.cycle_breaks;
        stats.cycle_breaks = cycle_breaks;
        debug_assert_eq!(out.len(), n);
    }
}

/// MPVONC phase III: iterative depth-first search along the behind relation.
struct Search<'a> {
    /// 0 unvisited, 1 on the stack, 2 emitted.
    state: &'a mut Vec<u8>,
    stack: &'a mut Vec<(u32, u8)>,
    behind: &'a [u8],
    adj: &'a [[u32; 4]],
    cycle_breaks: usize,
}

impl Search<'_> {
    /// Emits `root` and every unemitted tet behind it, each after all tets behind it.
    fn run(&mut self, root: u32, out: &mut Vec<u32>) {
        if self.state[root as usize] != 0 {
            return;
        }
        self.state[root as usize] = 1;
        self.stack.push((root, 0));
        while let Some(top) = self.stack.last_mut() {
            let (t, f) = *top;
            if f == 4 {
                self.stack.pop();
                self.state[t as usize] = 2;
                out.push(t);
                continue;
            }
            top.1 += 1;
            if self.behind[t as usize] & (1 << f) != 0 {
                let nb = self.adj[t as usize][f as usize];
                match self.state[nb as usize] {
                    0 => {
                        self.state[nb as usize] = 1;
                        self.stack.push((nb, 0));
                    }
                    // A back edge: `nb` is an ancestor on the stack, so this edge closes a cycle.
                    1 => self.cycle_breaks += 1,
                    _ => {}
                }
            }
        }
    }
}

/// How well an order respects the exact behind relation across interior faces.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OrderCheck {
    /// Interior faces that order their two tets (not edge-on).
    pub ordering_faces: usize,
    /// Of those, faces whose front tet is drawn before its behind tet.
    pub violations: usize,
}

/// Counts the interior faces across which `order` (back to front) draws the front tet first:
/// 0 for a valid visibility order of a convex acyclic mesh. The harness reports it beside the
/// image error of each order.
pub fn check_back_to_front(mesh: &TetMesh, camera: &Camera, order: &[u32]) -> OrderCheck {
    let mut position = vec![u32::MAX; mesh.num_tets()];
    for (i, &t) in order.iter().enumerate() {
        position[t as usize] = i as u32;
    }
    let eye = Eye::of(camera);
    let tol = 1e-12 * mesh.bounds().diagonal().max(1e-300);
    let adj = mesh.adjacency();
    let per_tet: Vec<(usize, usize)> = (0..mesh.num_tets())
        .into_par_iter()
        .map(|t| {
            let (mut faces, mut bad) = (0, 0);
            for (f, &nb) in adj[t].iter().enumerate() {
                if nb == NO_NEIGHBOUR || (nb as usize) < t {
                    continue;
                }
                let [a, b, c] =
                    TET_FACES[f].map(|l| mesh.points[mesh.tets[t][l] as usize].map(|x| x as f64));
                let s = eye_side(&plane_of(a, b, c), &eye);
                if s.abs() <= tol {
                    continue;
                }
                faces += 1;
                // s > 0: the eye sees face f from outside t, so nb is in front and t behind.
                let (back, front) = if s > 0.0 {
                    (t, nb as usize)
                } else {
                    (nb as usize, t)
                };
                if position[back] >= position[front] {
                    bad += 1;
                }
            }
            (faces, bad)
        })
        .collect();
    let (ordering_faces, violations) = per_tet.iter().fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    OrderCheck {
        ordering_faces,
        violations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_names_round_trip() {
        for o in VisibilityOrder::ALL
            .into_iter()
            .chain([VisibilityOrder::CentroidBucket { slabs: 7 }])
        {
            assert_eq!(o.to_string().parse::<VisibilityOrder>().unwrap(), o);
        }
        assert_eq!(
            "bucket".parse::<VisibilityOrder>().unwrap(),
            VisibilityOrder::CentroidBucket { slabs: 20 }
        );
        assert_eq!(VisibilityOrder::default().to_string(), "radix");
        assert!("bucket:0".parse::<VisibilityOrder>().is_err());
        assert!("painter".parse::<VisibilityOrder>().is_err());
    }
}
