//! The checked tetrahedral mesh every renderer and the reference consume.
//!
//! Construction normalises the mesh once (positive orientation, degenerate cells dropped,
//! values finite, indices in range); derived data (adjacency, boundary, faces, gradients…) is
//! computed on first use and cached, so a renderer pays only for what it reads.

use std::collections::HashMap;
use std::sync::OnceLock;

use rayon::prelude::*;

use crate::error::ErrorKind;

/// Face `i` of a tet is the one opposite its vertex `i`, wound counter-clockwise seen from
/// outside (right-hand normal points out of a positively oriented tet).
pub const TET_FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

/// Marks "no neighbour" in [`TetMesh::adjacency`].
pub const NO_NEIGHBOUR: u32 = u32::MAX;

/// Axis-aligned bounding box in f64.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Aabb {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

impl Aabb {
    pub fn of_points(points: &[[f32; 3]]) -> Aabb {
        let mut min = [f64::INFINITY; 3];
        let mut max = [f64::NEG_INFINITY; 3];
        for p in points {
            for a in 0..3 {
                min[a] = min[a].min(p[a] as f64);
                max[a] = max[a].max(p[a] as f64);
            }
        }
        Aabb { min, max }
    }
    pub fn center(&self) -> [f64; 3] {
        [0, 1, 2].map(|a| 0.5 * (self.min[a] + self.max[a]))
    }
    pub fn extent(&self) -> [f64; 3] {
        [0, 1, 2].map(|a| self.max[a] - self.min[a])
    }
    /// Length of the diagonal; the unit of the transfer function's extinction.
    pub fn diagonal(&self) -> f64 {
        let e = self.extent();
        (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt()
    }
}

/// What construction changed or tolerated, reported by `tetbench datasets info`.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct RepairReport {
    /// Tets of (numerically) zero volume, removed.
    pub degenerate_dropped: usize,
    /// Tets given in negative orientation, reordered to positive.
    pub inverted_fixed: usize,
    /// Points referenced by no tet (kept, harmless).
    pub unused_points: usize,
    /// Human-readable notes (e.g. "cell data averaged to points", "IBLANK present").
    pub warnings: Vec<String>,
}

/// A boundary face: tet and local face index (see [`TET_FACES`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BoundaryFace {
    pub tet: u32,
    pub face: u8,
}

impl BoundaryFace {
    /// Vertex indices of the face, wound so that its normal points out of the mesh.
    pub fn vertices(&self, mesh: &TetMesh) -> [u32; 3] {
        let t = mesh.tets[self.tet as usize];
        TET_FACES[self.face as usize].map(|i| t[i])
    }
}

/// The unique triangles of the mesh (HAVS rasterises each once).
#[derive(Debug, Clone, Default)]
pub struct UniqueFaces {
    pub faces: Vec<[u32; 3]>,
    /// `true` for faces on the mesh boundary (one incident tet).
    pub boundary: Vec<bool>,
}

/// Edge length and shape statistics (slivers matter to the HAVS k-buffer, §4 of the paper).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct QualityStats {
    pub min_edge: f64,
    pub max_edge: f64,
    pub mean_edge: f64,
    /// Aspect ratio = longest edge / (2·√6 · inradius): 1 for the regular tet.
    pub max_aspect_ratio: f64,
    pub mean_aspect_ratio: f64,
    /// Tets whose aspect ratio exceeds [`QualityStats::SLIVER_ASPECT`].
    pub slivers: usize,
}

impl QualityStats {
    pub const SLIVER_ASPECT: f64 = 10.0;
}

#[derive(Default)]
struct DerivedCache {
    bounds: OnceLock<Aabb>,
    adjacency: OnceLock<Vec<[u32; 4]>>,
    boundary: OnceLock<Vec<BoundaryFace>>,
    gradients: OnceLock<Vec<[f32; 3]>>,
    normals: OnceLock<Vec<[[f32; 3]; 4]>>,
    quality: OnceLock<QualityStats>,
    convex: OnceLock<bool>,
    hash: OnceLock<String>,
    scalar_range: OnceLock<(f32, f32)>,
}

impl Clone for DerivedCache {
    fn clone(&self) -> Self {
        DerivedCache::default()
    }
}

/// A checked tetrahedral mesh with one point scalar.
#[derive(Clone)]
pub struct TetMesh {
    /// Short name for reports (data set name or file stem).
    pub name: String,
    pub points: Vec<[f32; 3]>,
    /// One value per point.
    pub scalars: Vec<f32>,
    pub scalar_name: String,
    /// Every tet positively oriented and of non-zero volume.
    pub tets: Vec<[u32; 4]>,
    pub repair: RepairReport,
    /// The regular grid this mesh was split from (volume files, generated volumes), for
    /// renderers that work on voxels (`splat`); `None` for unstructured meshes. When set, mesh
    /// point `i` is grid point `i` (same position and value; x fastest), and the tets split
    /// the grid's cells (every cell, or for generated volumes with compact support only the
    /// cells with a non-zero corner: see `crate::gen_volume`). Other renderers ignore it.
    pub source_grid: Option<std::sync::Arc<crate::grid::VoxelGrid>>,
    cache: DerivedCache,
}

impl std::fmt::Debug for TetMesh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TetMesh")
            .field("name", &self.name)
            .field("points", &self.points.len())
            .field("tets", &self.tets.len())
            .field("scalar_name", &self.scalar_name)
            .field("repair", &self.repair)
            .field("source_grid", &self.source_grid.as_ref().map(|g| g.dims))
            .finish()
    }
}

/// Six times the signed volume of a tet (the determinant of its edge vectors), in f64.
pub fn signed_volume6(p: [[f64; 3]; 4]) -> f64 {
    let e1 = sub(p[1], p[0]);
    let e2 = sub(p[2], p[0]);
    let e3 = sub(p[3], p[0]);
    dot(e1, cross(e2, e3))
}

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// A tet is degenerate when its volume is below this fraction of the cube of its longest edge.
/// (A regular tet has V/l³ ≈ 0.118; rounding of f32 coordinates gives ~1e-7.)
const DEGENERATE_RELATIVE_VOLUME: f64 = 1e-9;

impl TetMesh {
    /// Checks and normalises a mesh. `ErrorKind` (without a path) is returned for faults the
    /// caller attaches to its file.
    pub fn new(
        name: impl Into<String>,
        points: Vec<[f32; 3]>,
        scalars: Vec<f32>,
        scalar_name: impl Into<String>,
        tets: Vec<[u32; 4]>,
    ) -> Result<TetMesh, ErrorKind> {
        if scalars.len() != points.len() {
            return Err(ErrorKind::CountMismatch {
                what: "point scalars".into(),
                expected: points.len() as u64,
                found: scalars.len() as u64,
            });
        }
        if points.len() > u32::MAX as usize {
            return Err(ErrorKind::IndexOverflow {
                what: "points".into(),
                count: points.len() as u64,
            });
        }
        for (i, p) in points.iter().enumerate() {
            if let Some(v) = p.iter().find(|v| !v.is_finite()) {
                return Err(ErrorKind::NonFinite {
                    what: "point".into(),
                    index: i as u64,
                    value: *v as f64,
                });
            }
        }
        if let Some((i, v)) = scalars.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(ErrorKind::NonFinite {
                what: "scalar of point".into(),
                index: i as u64,
                value: *v as f64,
            });
        }
        let n = points.len() as u64;
        for t in &tets {
            if let Some(&bad) = t.iter().find(|&&v| v as u64 >= n) {
                return Err(ErrorKind::IndexOutOfRange {
                    what: "point".into(),
                    index: bad as u64,
                    limit: n,
                });
            }
        }
        let mut repair = RepairReport::default();
        let orient: Vec<Option<[u32; 4]>> = tets
            .par_iter()
            .map(|&t| {
                let p = t.map(|v| points[v as usize].map(|c| c as f64));
                let v6 = signed_volume6(p);
                let mut lmax2: f64 = 0.0;
                for i in 0..4 {
                    for j in i + 1..4 {
                        let d = sub(p[i], p[j]);
                        lmax2 = lmax2.max(dot(d, d));
                    }
                }
                let lmax3 = lmax2 * lmax2.sqrt();
                // Written so that a NaN volume also counts as degenerate.
                #[allow(clippy::neg_cmp_op_on_partial_ord)]
                let degenerate = !(v6.abs() / 6.0 > DEGENERATE_RELATIVE_VOLUME * lmax3);
                if degenerate {
                    None
                } else if v6 < 0.0 {
                    Some([t[0], t[2], t[1], t[3]])
                } else {
                    Some(t)
                }
            })
            .collect();
        let mut kept = Vec::with_capacity(tets.len());
        for (orig, o) in tets.iter().zip(orient) {
            match o {
                None => repair.degenerate_dropped += 1,
                Some(t) => {
                    if t != *orig {
                        repair.inverted_fixed += 1;
                    }
                    kept.push(t);
                }
            }
        }
        if kept.is_empty() {
            let why = if repair.degenerate_dropped > 0 {
                format!(" ({} degenerate tets dropped)", repair.degenerate_dropped)
            } else {
                String::new()
            };
            return Err(ErrorKind::EmptyMesh(why));
        }
        let mut used = vec![false; points.len()];
        for t in &kept {
            for &v in t {
                used[v as usize] = true;
            }
        }
        repair.unused_points = used.iter().filter(|u| !**u).count();
        Ok(TetMesh {
            name: name.into(),
            points,
            scalars,
            scalar_name: scalar_name.into(),
            tets: kept,
            repair,
            source_grid: None,
            cache: DerivedCache::default(),
        })
    }

    pub fn num_points(&self) -> usize {
        self.points.len()
    }
    pub fn num_tets(&self) -> usize {
        self.tets.len()
    }

    /// The four corners of tet `t` in f64.
    pub fn tet_points(&self, t: usize) -> [[f64; 3]; 4] {
        self.tets[t].map(|v| self.points[v as usize].map(|c| c as f64))
    }

    pub fn bounds(&self) -> Aabb {
        *self.cache.bounds.get_or_init(|| {
            // Only points used by tets count: unused points must not move the camera.
            let mut min = [f64::INFINITY; 3];
            let mut max = [f64::NEG_INFINITY; 3];
            for t in &self.tets {
                for &v in t {
                    let p = self.points[v as usize];
                    for a in 0..3 {
                        min[a] = min[a].min(p[a] as f64);
                        max[a] = max[a].max(p[a] as f64);
                    }
                }
            }
            Aabb { min, max }
        })
    }

    /// (min, max) of the point scalar over points used by tets.
    pub fn scalar_range(&self) -> (f32, f32) {
        *self.cache.scalar_range.get_or_init(|| {
            let mut lo = f32::INFINITY;
            let mut hi = f32::NEG_INFINITY;
            for t in &self.tets {
                for &v in t {
                    let s = self.scalars[v as usize];
                    lo = lo.min(s);
                    hi = hi.max(s);
                }
            }
            (lo, hi)
        })
    }

    /// `adjacency()[t][f]` is the tet across face `f` of tet `t`, or [`NO_NEIGHBOUR`].
    /// Faces shared by more than two tets (non-manifold input) are treated as boundary.
    pub fn adjacency(&self) -> &[[u32; 4]] {
        self.cache.adjacency.get_or_init(|| {
            let mut keys: Vec<([u32; 3], u32)> = self
                .tets
                .par_iter()
                .enumerate()
                .flat_map_iter(|(t, tet)| {
                    (0..4).map(move |f| {
                        let mut k = TET_FACES[f].map(|i| tet[i]);
                        k.sort_unstable();
                        (k, (t as u32) * 4 + f as u32)
                    })
                })
                .collect();
            keys.par_sort_unstable();
            let mut adj = vec![[NO_NEIGHBOUR; 4]; self.tets.len()];
            let mut i = 0;
            while i < keys.len() {
                let mut j = i + 1;
                while j < keys.len() && keys[j].0 == keys[i].0 {
                    j += 1;
                }
                if j - i == 2 {
                    let (a, b) = (keys[i].1, keys[i + 1].1);
                    adj[(a / 4) as usize][(a % 4) as usize] = b / 4;
                    adj[(b / 4) as usize][(b % 4) as usize] = a / 4;
                }
                i = j;
            }
            adj
        })
    }

    /// Faces with no neighbour, in tet order.
    pub fn boundary_faces(&self) -> &[BoundaryFace] {
        self.cache.boundary.get_or_init(|| {
            let adj = self.adjacency();
            let mut out = Vec::new();
            for (t, a) in adj.iter().enumerate() {
                for (f, &n) in a.iter().enumerate() {
                    if n == NO_NEIGHBOUR {
                        out.push(BoundaryFace {
                            tet: t as u32,
                            face: f as u8,
                        });
                    }
                }
            }
            out
        })
    }

    /// Every triangle once: interior faces from the lower-numbered tet, boundary faces outward.
    /// Built on each call and not kept (unlike the adjacency it is made from): its one user,
    /// HAVS's prepare, turns it into its own face array at once, and a cached copy would hold
    /// 13 bytes a face (520 MB at 20 M tets) for the rest of the run.
    pub fn unique_faces(&self) -> UniqueFaces {
        let adj = self.adjacency();
        let mut faces = Vec::with_capacity(self.tets.len() * 2 + 64);
        let mut boundary = Vec::with_capacity(faces.capacity());
        for (t, a) in adj.iter().enumerate() {
            for (f, &n) in a.iter().enumerate() {
                if n == NO_NEIGHBOUR || (n as usize) > t {
                    faces.push(TET_FACES[f].map(|i| self.tets[t][i]));
                    boundary.push(n == NO_NEIGHBOUR);
                }
            }
        }
        UniqueFaces { faces, boundary }
    }

    /// Outward unit normal of each face of each tet (face order [`TET_FACES`]), computed once
    /// for the whole mesh and kept (48 bytes a tet).
    pub fn face_normals(&self) -> &[[[f32; 3]; 4]] {
        self.cache.normals.get_or_init(|| {
            (0..self.tets.len())
                .into_par_iter()
                .map(|t| self.tet_face_normals(t))
                .collect()
        })
    }

    /// The entry of [`Self::face_normals`] for tet `t`, computed alone (nothing kept).
    pub fn tet_face_normals(&self, t: usize) -> [[f32; 3]; 4] {
        let p = self.tet_points(t);
        TET_FACES.map(|[a, b, c]| {
            let n = cross(sub(p[b], p[a]), sub(p[c], p[a]));
            let l = norm(n).max(f64::MIN_POSITIVE);
            n.map(|x| (x / l) as f32)
        })
    }

    /// The constant gradient of the linearly interpolated scalar in each tet.
    pub fn scalar_gradients(&self) -> &[[f32; 3]] {
        self.cache.gradients.get_or_init(|| {
            (0..self.tets.len())
                .into_par_iter()
                .map(|t| {
                    let p = self.tet_points(t);
                    let s = self.tets[t].map(|v| self.scalars[v as usize] as f64);
                    let g = linear_gradient(p, s);
                    g.map(|x| x as f32)
                })
                .collect()
        })
    }

    /// Edge and shape statistics.
    pub fn quality(&self) -> &QualityStats {
        self.cache.quality.get_or_init(|| {
            let per_tet: Vec<(f64, f64, f64, f64)> = (0..self.tets.len())
                .into_par_iter()
                .map(|t| {
                    let p = self.tet_points(t);
                    let (mut lmin, mut lmax, mut lsum) = (f64::INFINITY, 0.0f64, 0.0);
                    for i in 0..4 {
                        for j in i + 1..4 {
                            let l = norm(sub(p[i], p[j]));
                            lmin = lmin.min(l);
                            lmax = lmax.max(l);
                            lsum += l;
                        }
                    }
                    let volume = signed_volume6(p).abs() / 6.0;
                    let area: f64 = TET_FACES
                        .iter()
                        .map(|&[a, b, c]| 0.5 * norm(cross(sub(p[b], p[a]), sub(p[c], p[a]))))
                        .sum();
                    let inradius = 3.0 * volume / area;
                    let aspect = lmax / (2.0 * 6f64.sqrt() * inradius);
                    (lmin, lmax, lsum, aspect)
                })
                .collect();
            let mut q = QualityStats {
                min_edge: f64::INFINITY,
                ..Default::default()
            };
            let mut lsum = 0.0;
            let mut asum = 0.0;
            for &(lmin, lmax, ls, aspect) in &per_tet {
                q.min_edge = q.min_edge.min(lmin);
                q.max_edge = q.max_edge.max(lmax);
                lsum += ls;
                asum += aspect;
                q.max_aspect_ratio = q.max_aspect_ratio.max(aspect);
                if aspect > QualityStats::SLIVER_ASPECT {
                    q.slivers += 1;
                }
            }
            // Edges are counted once per incident tet; a mean over tet-edges is what the
            // k-buffer analysis needs (fragment spacing), so no deduplication.
            q.mean_edge = lsum / (6 * per_tet.len()).max(1) as f64;
            q.mean_aspect_ratio = asum / per_tet.len().max(1) as f64;
            q
        })
    }

    /// Whether the boundary is convex. A closed, connected surface that is locally convex at
    /// every edge is convex (Tietze's theorem), so it suffices to check, for each boundary edge,
    /// that neither adjacent face's far vertex lies in front of the other face's plane, and
    /// that the boundary is one connected surface (a hollow shell's inner sphere is a second
    /// component). Linear in the boundary size, unlike the all-pairs face/vertex test.
    pub fn is_convex(&self) -> bool {
        *self.cache.convex.get_or_init(|| {
            let bfaces = self.boundary_faces();
            let tris: Vec<[u32; 3]> = bfaces.iter().map(|f| f.vertices(self)).collect();
            let mut edges: Vec<((u32, u32), u32)> = tris
                .iter()
                .enumerate()
                .flat_map(|(i, t)| {
                    (0..3).map(move |e| {
                        (
                            (t[e].min(t[(e + 1) % 3]), t[e].max(t[(e + 1) % 3])),
                            i as u32,
                        )
                    })
                })
                .collect();
            edges.par_sort_unstable();
            let tol = 1e-6 * self.bounds().diagonal();
            let point = |v: u32| self.points[v as usize].map(|c| c as f64);
            let plane = |t: [u32; 3]| {
                let [a, b, c] = t.map(point);
                let n = cross(sub(b, a), sub(c, a));
                let l = norm(n);
                (a, if l > 0.0 { n.map(|x| x / l) } else { [0.0; 3] })
            };
            let mut parent: Vec<u32> = (0..tris.len() as u32).collect();
            fn find(parent: &mut [u32], mut x: u32) -> u32 {
                while parent[x as usize] != x {
                    parent[x as usize] = parent[parent[x as usize] as usize];
                    x = parent[x as usize];
                }
                x
            }
            for pair in edges.chunk_by(|a, b| a.0 == b.0) {
                // A boundary edge shared by other than two boundary faces: the boundary is not a
                // simple closed surface (e.g. two blocks touching along an edge).
                let [(edge, f1), (_, f2)] = pair else {
                    return false;
                };
                for (f, g) in [(*f1, *f2), (*f2, *f1)] {
                    let (a, n) = plane(tris[f as usize]);
                    let far = tris[g as usize]
                        .into_iter()
                        .find(|&v| v != edge.0 && v != edge.1);
                    if let Some(v) = far {
                        if dot(sub(point(v), a), n) > tol {
                            return false;
                        }
                    }
                }
                let (r1, r2) = (find(&mut parent, *f1), find(&mut parent, *f2));
                parent[r1 as usize] = r2;
            }
            let root = find(&mut parent, 0);
            (0..tris.len() as u32).all(|f| find(&mut parent, f) == root)
        })
    }

    /// A stable content hash (points, scalars, tets), used to key cached reference images.
    pub fn content_hash(&self) -> &str {
        self.cache.hash.get_or_init(|| {
            let mut h = blake3::Hasher::new();
            for p in &self.points {
                for c in p {
                    h.update(&c.to_le_bytes());
                }
            }
            for s in &self.scalars {
                h.update(&s.to_le_bytes());
            }
            for t in &self.tets {
                for v in t {
                    h.update(&v.to_le_bytes());
                }
            }
            h.finalize().to_hex()[..16].to_string()
        })
    }

    /// Replaces the point scalar (e.g. another PLOT3D Q field), keeping the geometry and the
    /// derived data that does not depend on the scalar.
    pub fn with_scalars(
        mut self,
        name: impl Into<String>,
        scalars: Vec<f32>,
    ) -> Result<TetMesh, ErrorKind> {
        if scalars.len() != self.points.len() {
            return Err(ErrorKind::CountMismatch {
                what: "point scalars".into(),
                expected: self.points.len() as u64,
                found: scalars.len() as u64,
            });
        }
        if let Some((i, v)) = scalars.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(ErrorKind::NonFinite {
                what: "scalar of point".into(),
                index: i as u64,
                value: *v as f64,
            });
        }
        self.scalars = scalars;
        self.scalar_name = name.into();
        self.cache.gradients = OnceLock::new();
        self.cache.hash = OnceLock::new();
        self.cache.scalar_range = OnceLock::new();
        Ok(self)
    }
}

/// Gradient of the linear function taking values `s` at the corners `p` of a tet.
pub fn linear_gradient(p: [[f64; 3]; 4], s: [f64; 4]) -> [f64; 3] {
    // Solve [e1; e2; e3] g = [s1-s0, s2-s0, s3-s0] by Cramer's rule.
    let e = [sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0])];
    let d = [s[1] - s[0], s[2] - s[0], s[3] - s[0]];
    let det = dot(e[0], cross(e[1], e[2]));
    if det == 0.0 {
        return [0.0; 3];
    }
    // Rows of the inverse are cross products of the other two edges / det (transposed).
    let c0 = cross(e[1], e[2]);
    let c1 = cross(e[2], e[0]);
    let c2 = cross(e[0], e[1]);
    [0, 1, 2].map(|a| (c0[a] * d[0] + c1[a] * d[1] + c2[a] * d[2]) / det)
}

/// Groups equal face keys; used by readers that need to count shared faces.
pub fn face_multiplicity(tets: &[[u32; 4]]) -> HashMap<[u32; 3], u32> {
    let mut m = HashMap::new();
    for t in tets {
        for f in TET_FACES {
            let mut k = f.map(|i| t[i]);
            k.sort_unstable();
            *m.entry(k).or_insert(0) += 1;
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_tets() -> TetMesh {
        let points = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
        ];
        let scalars = vec![0.0, 1.0, 2.0, 3.0, 4.0];
        // Second tet given inverted on purpose.
        TetMesh::new("t", points, scalars, "s", vec![[0, 1, 2, 3], [1, 3, 2, 4]]).unwrap()
    }

    #[test]
    fn orientation_is_fixed_and_faces_point_out() {
        let m = two_tets();
        assert_eq!(m.repair.inverted_fixed, 1);
        for t in 0..m.num_tets() {
            assert!(signed_volume6(m.tet_points(t)) > 0.0);
            let p = m.tet_points(t);
            let c = [0, 1, 2].map(|a| p.iter().map(|q| q[a]).sum::<f64>() / 4.0);
            for (f, n) in m.face_normals()[t].iter().enumerate() {
                let a = p[TET_FACES[f][0]];
                assert!(
                    dot(sub(a, c), n.map(|x| x as f64)) > 0.0,
                    "face normal points inward"
                );
            }
        }
    }

    #[test]
    fn adjacency_and_boundary() {
        let m = two_tets();
        let shared = m.adjacency()[0].iter().filter(|&&n| n == 1).count();
        assert_eq!(shared, 1);
        assert_eq!(m.boundary_faces().len(), 6);
        assert_eq!(m.unique_faces().faces.len(), 7);
        // A triangular bipyramid: convex.
        assert!(m.is_convex());
    }

    #[test]
    fn degenerate_dropped_and_empty_is_error() {
        let points = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
        ];
        let err = TetMesh::new("d", points, vec![0.0; 4], "s", vec![[0, 1, 2, 3]]).unwrap_err();
        assert!(matches!(err, ErrorKind::EmptyMesh(_)));
    }

    #[test]
    fn gradient_of_linear_field_is_exact() {
        let p = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 3.0, 0.0],
            [0.0, 0.0, 5.0],
        ];
        let f = |q: [f64; 3]| 1.0 + 2.0 * q[0] - 3.0 * q[1] + 0.5 * q[2];
        let g = linear_gradient(p, p.map(f));
        assert!(
            (g[0] - 2.0).abs() < 1e-12 && (g[1] + 3.0).abs() < 1e-12 && (g[2] - 0.5).abs() < 1e-12
        );
    }
}
