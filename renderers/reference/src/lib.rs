//! The exact CPU reference renderer: for every pixel centre, the ray is followed through the
//! mesh tet by tet in f64 and each tet segment is integrated exactly for its linearly varying
//! scalar through the piecewise-linear transfer function
//! ([`render_core::preintegration::SegmentIntegrator`]).
//!
//! Method (Bunyk, Kaufman & Silva 1997, "Simple, fast, and robust ray casting of irregular
//! grids"): the boundary faces are binned into screen tiles; a pixel tests the faces of its
//! tile and sorts the entry hits by distance. From each entry the ray walks tet to tet through
//! the face adjacency (exit face = nearest face plane the ray leaves through); when it leaves
//! through a boundary face it continues with the next entry hit further along, so non-convex
//! meshes re-enter.
//!
//! Robustness (rays through edges and vertices, e.g. axis-aligned views of structured grids):
//! every tet is walked at most once per ray (visit stamps), the composited interval only moves
//! forward (so nothing is counted twice), and wherever the walk makes no progress or the next
//! tet was already visited, the point reached is located among the tets sharing the smallest
//! sub-simplex (face, edge, vertex) it lies on, continuing in the one the ray stays in longest.
//! Only pieces shorter than 1e-12 of the bounding-box diagonal can be skipped that way.
//!
//! The eye must lie outside the mesh (cameras fitted with `Camera::fit` always do): rays start
//! at the first boundary face they cross.
//!
//! [`dense_sampling`] is an independent brute-force integrator (point location at small steps)
//! used only to test this one (`dense.rs`); [`render_cached`] keeps images on disk, keyed by
//! the reference code's own hash ([`CODE_HASH`], `cache.rs`). [`RenderStats::lost_rays`] counts
//! the rays whose walk could not be continued; the cache keeps that count with the image.

// `!(x > 0.0)` is used on purpose: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use datasets::{TetMesh, NO_NEIGHBOUR, TET_FACES};
use glam::{DMat4, DVec3, DVec4};
use rayon::prelude::*;
use render_core::preintegration::{composite_front_to_back, SegmentIntegrator};
use render_core::{Camera, Image, Optics, Ray};

mod cache;
mod dense;

pub use cache::{
    cache_file, cache_key_for, read_cached, read_cached_reference, render_cached,
    render_cached_reference, Reference, CODE_HASH,
};
pub use dense::dense_sampling;

/// Rays stop once their opacity exceeds this (nothing behind can change a pixel by > 1e-9).
pub const OPAQUE: f64 = 1.0 - 1e-9;

/// Screen tiles (pixels) that boundary faces are binned into.
const TILE: u32 = 8;

/// Counters of one reference render.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct RenderStats {
    /// Pixels traced.
    pub rays: u64,
    /// Rays that entered the mesh at least once.
    pub rays_hit: u64,
    /// Tet segments integrated.
    pub segments: u64,
    /// Walks that started after the ray had left the mesh once (non-convex meshes).
    pub reentries: u64,
    /// Walks continued by point location (after stalling at an edge or vertex, or leaving a
    /// tet near an edge into a tet other than the exit face's neighbour).
    pub relocations: u64,
    /// Entry hits ignored because the ray was already past them (numerically duplicated hits).
    pub skipped_entries: u64,
    /// Boundary faces tested against rays.
    pub face_tests: u64,
    /// Rays that stopped early at opacity > 1 − 1e-9.
    pub terminated: u64,
    /// Pixel rays at least one of whose walks ended early, not by leaving the mesh: point
    /// location found only already-visited tets continuing the ray (the visit stamps that keep
    /// each tet to one walk per ray blocked it), so the rest of that walk's path is missing
    /// from the pixel unless a later entry hit covers it. Opacity termination and leaving
    /// through the boundary (including grazing entries that integrate nothing) are normal
    /// exits; the walk has no other way to end.
    pub lost_rays: u64,
}

impl RenderStats {
    fn add(&mut self, o: &RenderStats) {
        self.rays += o.rays;
        self.rays_hit += o.rays_hit;
        self.segments += o.segments;
        self.reentries += o.reentries;
        self.relocations += o.relocations;
        self.skipped_entries += o.skipped_entries;
        self.face_tests += o.face_tests;
        self.terminated += o.terminated;
        self.lost_rays += o.lost_rays;
    }
}

/// A boundary face in f64 with its plane (outward unit normal `n`, n·x = `w`).
#[derive(Debug, Clone, Copy)]
struct BFace {
    p: [DVec3; 3],
    n: DVec3,
    w: f64,
    /// 2 × area, for barycentric coordinates.
    area2: f64,
    tet: u32,
}

/// Per-mesh data reused across cameras and transfer functions: face planes, the linear scalar
/// of each tet, the vertex→tet incidence and the boundary faces.
pub struct Prepared<'m> {
    mesh: &'m TetMesh,
    /// Per tet, per face (order [`TET_FACES`]): outward unit normal xyz and offset w (n·x = w).
    planes: Vec<[[f64; 4]; 4]>,
    /// Per tet, per vertex: distance from the vertex to the opposite face plane (> 0).
    heights: Vec<[f64; 4]>,
    /// Per tet: the scalar as s(x) = g·x + c, stored [gx, gy, gz, c].
    scalar: Vec<[f64; 4]>,
    star_offsets: Vec<u32>,
    star_tets: Vec<u32>,
    bfaces: Vec<BFace>,
    /// Bounding-box diagonal: the scale of every tolerance.
    scale: f64,
}

/// How point location after a stall or an unnamed exit ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Relocation {
    /// The unvisited tet the ray stays in longest.
    Found(usize),
    /// No tet around the point continues the ray: it leaves the mesh here.
    Exit,
    /// Only tets this ray already walked continue it: the walk cannot go on (a lost ray).
    Blocked,
}

/// Face planes, vertex heights and the linear scalar of one tet.
type TetData = ([[f64; 4]; 4], [f64; 4], [f64; 4]);

impl<'m> Prepared<'m> {
    pub fn new(mesh: &'m TetMesh) -> Prepared<'m> {
        let n = mesh.num_tets();
        let per_tet: Vec<TetData> = (0..n)
            .into_par_iter()
            .map(|t| {
                let p = mesh.tet_points(t).map(DVec3::from);
                let mut planes = [[0.0; 4]; 4];
                let mut heights = [0.0; 4];
                for (f, [a, b, c]) in TET_FACES.iter().enumerate() {
                    let nrm = (p[*b] - p[*a]).cross(p[*c] - p[*a]).normalize_or_zero();
                    let w = nrm.dot(p[*a]);
                    planes[f] = [nrm.x, nrm.y, nrm.z, w];
                    heights[f] = (w - nrm.dot(p[f])).max(f64::MIN_POSITIVE);
                }
                let s = mesh.tets[t].map(|v| mesh.scalars[v as usize] as f64);
                let g = DVec3::from(datasets::mesh::linear_gradient(p.map(|q| q.into()), s));
                // Constant term about the centroid (smaller cancellation than about the origin).
                let centre = (p[0] + p[1] + p[2] + p[3]) * 0.25;
                let s_centre = 0.25 * (s[0] + s[1] + s[2] + s[3]);
                let c = s_centre - g.dot(centre);
                (planes, heights, [g.x, g.y, g.z, c])
            })
            .collect();
        let mut planes = Vec::with_capacity(n);
        let mut heights = Vec::with_capacity(n);
        let mut scalar = Vec::with_capacity(n);
        for (p, h, s) in per_tet {
            planes.push(p);
            heights.push(h);
            scalar.push(s);
        }
        // Vertex → incident tets (CSR).
        let mut counts = vec![0u32; mesh.num_points() + 1];
        for t in &mesh.tets {
            for &v in t {
                counts[v as usize + 1] += 1;
            }
        }
        for i in 1..counts.len() {
            counts[i] += counts[i - 1];
        }
        let mut fill = counts.clone();
        let mut star_tets = vec![0u32; counts[mesh.num_points()] as usize];
        for (ti, t) in mesh.tets.iter().enumerate() {
            for &v in t {
                star_tets[fill[v as usize] as usize] = ti as u32;
                fill[v as usize] += 1;
            }
        }
        let bfaces = mesh
            .boundary_faces()
            .iter()
            .map(|bf| {
                let p = bf
                    .vertices(mesh)
                    .map(|v| DVec3::from(mesh.points[v as usize].map(|c| c as f64)));
                let pl = planes[bf.tet as usize][bf.face as usize];
                let n = DVec3::new(pl[0], pl[1], pl[2]);
                BFace {
                    p,
                    n,
                    w: pl[3],
                    area2: (p[1] - p[0]).cross(p[2] - p[0]).dot(n),
                    tet: bf.tet,
                }
            })
            .collect();
        Prepared {
            mesh,
            planes,
            heights,
            scalar,
            star_offsets: counts,
            star_tets,
            bfaces,
            scale: mesh.bounds().diagonal().max(f64::MIN_POSITIVE),
        }
    }

    pub fn mesh(&self) -> &TetMesh {
        self.mesh
    }

    fn star(&self, v: u32) -> &[u32] {
        &self.star_tets
            [self.star_offsets[v as usize] as usize..self.star_offsets[v as usize + 1] as usize]
    }

    /// Interval [a, b] of ray parameters inside tet `t` (faces nearly parallel to the ray
    /// constrain nothing unless the ray is clearly outside them), and the exit face.
    #[inline]
    fn interval(&self, t: usize, o: DVec3, d: DVec3) -> Option<(f64, f64, usize)> {
        let mut a = f64::NEG_INFINITY;
        let mut b = f64::INFINITY;
        let mut exit = usize::MAX;
        for (f, pl) in self.planes[t].iter().enumerate() {
            let n = DVec3::new(pl[0], pl[1], pl[2]);
            let denom = n.dot(d);
            let h = pl[3] - n.dot(o);
            if denom > 1e-14 {
                let tf = h / denom;
                if tf < b {
                    b = tf;
                    exit = f;
                }
            } else if denom < -1e-14 {
                a = a.max(h / denom);
            } else if h < -1e-10 * self.scale {
                return None;
            }
        }
        if exit == usize::MAX {
            return None;
        }
        Some((a, b, exit))
    }

    #[inline]
    fn scalar_at(&self, t: usize, x: DVec3) -> f64 {
        let s = self.scalar[t];
        s[0] * x.x + s[1] * x.y + s[2] * x.z + s[3]
    }

    /// Locates where the ray continues at parameter `t` after stalling in tet `from`: among
    /// the tets sharing the smallest sub-simplex of `from` that the point lies on, the
    /// unvisited one the ray stays in longest ([`Relocation::Found`]); when there is none, whether
    /// some visited tet would have continued the ray ([`Relocation::Blocked`]) or none does.
    fn relocate(
        &self,
        from: usize,
        t: f64,
        o: DVec3,
        d: DVec3,
        stamps: &[u32],
        ray_id: u32,
    ) -> Relocation {
        let x = o + d * t;
        let tet = self.mesh.tets[from];
        let mut lam = [0.0; 4];
        for (f, pl) in self.planes[from].iter().enumerate() {
            lam[f] = (pl[3] - DVec3::new(pl[0], pl[1], pl[2]).dot(x)) / self.heights[from][f];
        }
        let mut order = [0usize, 1, 2, 3];
        order.sort_by(|&i, &j| lam[j].total_cmp(&lam[i]));
        let mut k = order.iter().take_while(|&&i| lam[i] > 1e-10).count().max(1);
        let eps_progress = 1e-12 * self.scale;
        let eps_entry = 1e-8 * self.scale;
        let mut blocked = false;
        loop {
            let verts: Vec<u32> = order[..k].iter().map(|&i| tet[i]).collect();
            let pivot = *verts.iter().min_by_key(|&&v| self.star(v).len()).unwrap();
            let mut best: Option<(usize, f64)> = None;
            for &c in self.star(pivot) {
                let c = c as usize;
                if !verts.iter().all(|v| self.mesh.tets[c].contains(v)) {
                    continue;
                }
                if let Some((a, b, _)) = self.interval(c, o, d) {
                    if a <= t + eps_entry && b > t + eps_progress {
                        if stamps[c] == ray_id {
                            blocked = true;
                        } else if best.is_none_or(|(_, bb)| b > bb) {
                            best = Some((c, b));
                        }
                    }
                }
            }
            if let Some((c, _)) = best {
                return Relocation::Found(c);
            }
            // Widen to the next smaller sub-simplex only if the point is really close to it.
            if k == 1 || lam[order[k - 1]] > 1e-6 {
                return if blocked {
                    Relocation::Blocked
                } else {
                    Relocation::Exit
                };
            }
            k -= 1;
        }
    }

    /// Traces one ray; `hits` and `stamps` are per-thread scratch.
    fn trace(
        &self,
        integ: &SegmentIntegrator,
        optics: &Optics,
        ray: &Ray,
        faces: &[u32],
        scratch: &mut Scratch,
        stats: &mut RenderStats,
    ) -> [f64; 4] {
        let o = DVec3::from(ray.origin);
        let d = DVec3::from(ray.dir);
        stats.rays += 1;
        scratch.next_ray();
        let ray_id = scratch.ray_id;
        // Entry hits: boundary faces the ray crosses from outside to inside.
        scratch.hits.clear();
        for &fi in faces {
            let f = &self.bfaces[fi as usize];
            stats.face_tests += 1;
            let denom = f.n.dot(d);
            if !(denom < -1e-14) {
                continue;
            }
            let t = (f.w - f.n.dot(o)) / denom;
            let x = o + d * t;
            let l0 = (f.p[1] - x).cross(f.p[2] - x).dot(f.n) / f.area2;
            let l1 = (f.p[2] - x).cross(f.p[0] - x).dot(f.n) / f.area2;
            let l2 = 1.0 - l0 - l1;
            if l0 >= -1e-9 && l1 >= -1e-9 && l2 >= -1e-9 {
                scratch.hits.push((t, f.tet));
            }
        }
        if scratch.hits.is_empty() {
            return [0.0; 4];
        }
        scratch.hits.sort_by(|a, b| a.0.total_cmp(&b.0));
        let eps_progress = 1e-12 * self.scale;
        let eps_behind = 1e-8 * self.scale;
        let mut acc = [0.0f64; 4];
        let mut t_done = f64::NEG_INFINITY;
        let mut walks = 0u64;
        let mut lost = false;
        let hits = std::mem::take(&mut scratch.hits);
        'entries: for &(t_hit, start) in &hits {
            if t_hit < t_done - eps_behind {
                stats.skipped_entries += 1;
                continue;
            }
            if scratch.stamps[start as usize] == ray_id {
                continue;
            }
            let mut cur = start as usize;
            let mut t_cur = t_hit.max(t_done);
            let mut walk_counted = false;
            loop {
                scratch.stamps[cur] = ray_id;
                let relocated = match self.interval(cur, o, d) {
                    Some((_, b, exit)) if b > t_cur + eps_progress => {
                        let x0 = o + d * t_cur;
                        let x1 = o + d * b;
                        let s0 = optics.normalise(self.scalar_at(cur, x0));
                        let s1 = optics.normalise(self.scalar_at(cur, x1));
                        let seg = integ.integrate(s0, s1, (b - t_cur) / optics.length_unit);
                        composite_front_to_back(&mut acc, seg);
                        stats.segments += 1;
                        if !walk_counted {
                            walks += 1;
                            walk_counted = true;
                        }
                        t_cur = b;
                        t_done = b;
                        if acc[3] > OPAQUE {
                            stats.terminated += 1;
                            break 'entries;
                        }
                        let nb = self.mesh.adjacency()[cur][exit];
                        if nb != NO_NEIGHBOUR && scratch.stamps[nb as usize] != ray_id {
                            Relocation::Found(nb as usize)
                        } else {
                            // A boundary exit, unless the ray leaves near an edge or vertex
                            // into a tet the adjacency does not name.
                            match self.relocate(cur, t_cur, o, d, &scratch.stamps, ray_id) {
                                Relocation::Found(n) => {
                                    stats.relocations += 1;
                                    Relocation::Found(n)
                                }
                                other => other,
                            }
                        }
                    }
                    _ => match self.relocate(cur, t_cur, o, d, &scratch.stamps, ray_id) {
                        Relocation::Found(n) => {
                            stats.relocations += 1;
                            Relocation::Found(n)
                        }
                        other => other,
                    },
                };
                match relocated {
                    Relocation::Found(n) => cur = n,
                    Relocation::Exit => break,
                    Relocation::Blocked => {
                        lost = true;
                        break;
                    }
                }
            }
        }
        scratch.hits = hits;
        stats.lost_rays += lost as u64;
        if walks > 0 {
            stats.rays_hit += 1;
            stats.reentries += walks - 1;
        }
        acc
    }

    /// Renders one view. Rows are traced in parallel (rayon).
    pub fn render(&self, optics: &Optics, camera: &Camera) -> (Image, RenderStats) {
        let (w, h) = (camera.width, camera.height);
        let bins = self.bin_faces(camera);
        let tiles_x = w.div_ceil(TILE);
        let integ = SegmentIntegrator::new(&optics.tf);
        let mut pixels = vec![[0f32; 4]; (w * h) as usize];
        let stats = pixels
            .par_chunks_mut(w as usize)
            .enumerate()
            .map_init(
                || Scratch::new(self.mesh.num_tets()),
                |scratch, (y, row)| {
                    let mut st = RenderStats::default();
                    let ty = y as u32 / TILE;
                    for (x, px) in row.iter_mut().enumerate() {
                        let tile = (ty * tiles_x + x as u32 / TILE) as usize;
                        let faces = &bins.faces
                            [bins.offsets[tile] as usize..bins.offsets[tile + 1] as usize];
                        let ray = camera.pixel_ray(x as u32, y as u32);
                        let c = self.trace(&integ, optics, &ray, faces, scratch, &mut st);
                        *px = c.map(|v| v as f32);
                    }
                    st
                },
            )
            .reduce(RenderStats::default, |mut a, b| {
                a.add(&b);
                a
            });
        (
            Image {
                width: w,
                height: h,
                pixels,
            },
            stats,
        )
    }

    /// Bins every boundary face that can be an entry face for some pixel into the screen
    /// tiles its projection's bounding box (plus a pixel) overlaps.
    fn bin_faces(&self, camera: &Camera) -> Bins {
        let (w, h) = (camera.width, camera.height);
        let tiles_x = w.div_ceil(TILE);
        let tiles_y = h.div_ceil(TILE);
        let ntiles = (tiles_x * tiles_y) as usize;
        let vp: DMat4 = camera.view_proj();
        let eye = DVec3::from(camera.eye);
        let fwd = DVec3::from(camera.forward());
        let persp = camera.is_perspective();
        let ranges: Vec<Option<[u32; 4]>> = self
            .bfaces
            .par_iter()
            .map(|f| {
                // Faces turned away from every ray can never be entered.
                let facing = if persp {
                    f.n.dot(eye) - f.w
                } else {
                    -f.n.dot(fwd)
                };
                if facing < -1e-9 * self.scale {
                    return None;
                }
                let mut lo = [f64::INFINITY; 2];
                let mut hi = [f64::NEG_INFINITY; 2];
                for p in f.p {
                    let c = vp * DVec4::new(p.x, p.y, p.z, 1.0);
                    if !(c.w > 1e-12) {
                        return Some([0, 0, tiles_x - 1, tiles_y - 1]);
                    }
                    let px = (c.x / c.w + 1.0) * 0.5 * w as f64;
                    let py = (1.0 - c.y / c.w) * 0.5 * h as f64;
                    lo = [lo[0].min(px), lo[1].min(py)];
                    hi = [hi[0].max(px), hi[1].max(py)];
                }
                if hi[0] < -1.0 || hi[1] < -1.0 || lo[0] > w as f64 + 1.0 || lo[1] > h as f64 + 1.0
                {
                    return None;
                }
                let tx0 = ((lo[0] - 1.0).max(0.0) / TILE as f64) as u32;
                let ty0 = ((lo[1] - 1.0).max(0.0) / TILE as f64) as u32;
                let tx1 = (((hi[0] + 1.0).max(0.0) / TILE as f64) as u32).min(tiles_x - 1);
                let ty1 = (((hi[1] + 1.0).max(0.0) / TILE as f64) as u32).min(tiles_y - 1);
                Some([tx0.min(tiles_x - 1), ty0.min(tiles_y - 1), tx1, ty1])
            })
            .collect();
        let mut counts = vec![0u32; ntiles + 1];
        for r in ranges.iter().flatten() {
            for ty in r[1]..=r[3] {
                for tx in r[0]..=r[2] {
                    counts[(ty * tiles_x + tx) as usize + 1] += 1;
                }
            }
        }
        for i in 1..counts.len() {
            counts[i] += counts[i - 1];
        }
        let mut fill = counts.clone();
        let mut faces = vec![0u32; counts[ntiles] as usize];
        for (fi, r) in ranges.iter().enumerate() {
            if let Some(r) = r {
                for ty in r[1]..=r[3] {
                    for tx in r[0]..=r[2] {
                        let tile = (ty * tiles_x + tx) as usize;
                        faces[fill[tile] as usize] = fi as u32;
                        fill[tile] += 1;
                    }
                }
            }
        }
        Bins {
            offsets: counts,
            faces,
        }
    }
}

struct Bins {
    offsets: Vec<u32>,
    faces: Vec<u32>,
}

/// Per-thread scratch: entry hits and per-tet visit stamps.
struct Scratch {
    hits: Vec<(f64, u32)>,
    stamps: Vec<u32>,
    ray_id: u32,
}

impl Scratch {
    fn new(tets: usize) -> Scratch {
        Scratch {
            hits: Vec::with_capacity(64),
            stamps: vec![0; tets],
            ray_id: 0,
        }
    }
    fn next_ray(&mut self) {
        self.ray_id = self.ray_id.wrapping_add(1);
        if self.ray_id == 0 {
            self.stamps.iter_mut().for_each(|s| *s = 0);
            self.ray_id = 1;
        }
    }
}

/// The exact reference image of `mesh` seen by `camera` (premultiplied RGBA over black).
pub fn render(mesh: &TetMesh, optics: &Optics, camera: &Camera) -> Image {
    Prepared::new(mesh).render(optics, camera).0
}

/// [`render`] with its counters.
pub fn render_with_stats(mesh: &TetMesh, optics: &Optics, camera: &Camera) -> (Image, RenderStats) {
    Prepared::new(mesh).render(optics, camera)
}

#[cfg(test)]
mod tests {
    use super::*;
    use render_core::TransferFunction;

    /// Two tets sharing the face z = 0 (one above, one below) and a ray straight down through
    /// that face's interior.
    fn stacked_pair() -> TetMesh {
        let points = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.25, 0.25, 1.0],
            [0.25, 0.25, -1.0],
        ];
        let scalars = vec![0.0, 1.0, 0.5, 0.2, 0.8];
        TetMesh::new(
            "pair",
            points,
            scalars,
            "s",
            vec![[0, 1, 2, 3], [0, 1, 2, 4]],
        )
        .unwrap()
    }

    /// Traces the ray down through (0.2, 0.3); `pre_visit` tets are stamped as already walked
    /// by this ray before it starts (a synthetic stand-in for a walk that came back).
    fn trace_down(mesh: &TetMesh, pre_visit: &[usize]) -> RenderStats {
        let prepared = Prepared::new(mesh);
        let optics = Optics::for_mesh(TransferFunction::preset("low-opacity").unwrap(), mesh);
        let integ = SegmentIntegrator::new(&optics.tf);
        let faces: Vec<u32> = (0..prepared.bfaces.len() as u32).collect();
        let mut scratch = Scratch::new(mesh.num_tets());
        for &t in pre_visit {
            scratch.stamps[t] = scratch.ray_id + 1;
        }
        let ray = Ray {
            origin: [0.2, 0.3, 5.0],
            dir: [0.0, 0.0, -1.0],
        };
        let mut stats = RenderStats::default();
        prepared.trace(&integ, &optics, &ray, &faces, &mut scratch, &mut stats);
        stats
    }

    #[test]
    fn a_walk_through_both_tets_is_not_lost() {
        let stats = trace_down(&stacked_pair(), &[]);
        assert_eq!((stats.rays_hit, stats.segments, stats.lost_rays), (1, 2, 0));
    }

    #[test]
    fn a_walk_blocked_by_a_visited_tet_is_a_lost_ray() {
        let mesh = stacked_pair();
        // The lower tet is already stamped: the walk leaves the upper tet into it, point
        // location finds only that visited tet continuing the ray, and the walk ends there.
        let lower = (0..2)
            .find(|&t| mesh.tet_points(t).iter().any(|p| p[2] < 0.0))
            .unwrap();
        let stats = trace_down(&mesh, &[lower]);
        assert_eq!((stats.rays_hit, stats.segments, stats.lost_rays), (1, 1, 1));
        // The upper tet stamped instead: its only entry is skipped, nothing is walked and
        // nothing is lost (the lower tet has no entry face on this ray).
        let stats = trace_down(&mesh, &[1 - lower]);
        assert_eq!((stats.segments, stats.lost_rays), (0, 0));
    }

    #[test]
    fn leaving_through_the_boundary_is_a_normal_exit() {
        // The upper tet alone: the ray leaves through the boundary face z = 0.
        let points = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.25, 0.25, 1.0],
        ];
        let mesh = TetMesh::new(
            "one",
            points,
            vec![0.0, 1.0, 0.5, 0.2],
            "s",
            vec![[0, 1, 2, 3]],
        )
        .unwrap();
        let stats = trace_down(&mesh, &[]);
        assert_eq!((stats.rays_hit, stats.segments, stats.lost_rays), (1, 1, 0));
    }
}
