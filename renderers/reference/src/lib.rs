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
//! used only to test this one; [`render_cached`] keeps images on disk.

// `!(x > 0.0)` is used on purpose: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::io::Write;
use std::path::{Path, PathBuf};

use datasets::{TetMesh, NO_NEIGHBOUR, TET_FACES};
use glam::{DMat4, DVec3, DVec4};
use rayon::prelude::*;
use render_core::preintegration::{composite_front_to_back, SegmentIntegrator};
use render_core::{Camera, Image, Optics, Ray};

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
    /// unvisited one the ray stays in longest.
    fn relocate(
        &self,
        from: usize,
        t: f64,
        o: DVec3,
        d: DVec3,
        stamps: &[u32],
        ray_id: u32,
    ) -> Option<usize> {
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
        loop {
            let verts: Vec<u32> = order[..k].iter().map(|&i| tet[i]).collect();
            let pivot = *verts.iter().min_by_key(|&&v| self.star(v).len()).unwrap();
            let mut best: Option<(usize, f64)> = None;
            for &c in self.star(pivot) {
                let c = c as usize;
                if stamps[c] == ray_id || !verts.iter().all(|v| self.mesh.tets[c].contains(v)) {
                    continue;
                }
                if let Some((a, b, _)) = self.interval(c, o, d) {
                    if a <= t + eps_entry
                        && b > t + eps_progress
                        && best.is_none_or(|(_, bb)| b > bb)
                    {
                        best = Some((c, b));
                    }
                }
            }
            if let Some((c, _)) = best {
                return Some(c);
            }
            // Widen to the next smaller sub-simplex only if the point is really close to it.
            if k == 1 || lam[order[k - 1]] > 1e-6 {
                return None;
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
                let next = match self.interval(cur, o, d) {
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
                            Some(nb as usize)
                        } else {
                            // A boundary exit, unless the ray leaves near an edge or vertex
                            // into a tet the adjacency does not name.
                            self.relocate(cur, t_cur, o, d, &scratch.stamps, ray_id)
                                .inspect(|_| stats.relocations += 1)
                        }
                    }
                    _ => self
                        .relocate(cur, t_cur, o, d, &scratch.stamps, ray_id)
                        .inspect(|_| stats.relocations += 1),
                };
                match next {
                    Some(n) => cur = n,
                    None => break,
                }
            }
        }
        scratch.hits = hits;
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

    /// [`render_cached`] with this prepared mesh.
    pub fn render_cached(
        &self,
        optics: &Optics,
        camera: &Camera,
        cache_dir: &Path,
    ) -> anyhow::Result<Image> {
        let key = cache_key(self.mesh, optics, camera);
        let path = cache_path(cache_dir, &key);
        if let Some(img) = read_cache(&path, &key, camera.width, camera.height) {
            return Ok(img);
        }
        let (img, _) = self.render(optics, camera);
        write_cache(&path, &key, &img)?;
        Ok(img)
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

// ---------------------------------------------------------------------------------------------
// On-disk cache
// ---------------------------------------------------------------------------------------------

const CACHE_MAGIC: &[u8; 8] = b"TBREF\x00\x00\x01";
/// Bumped whenever the renderer's output could change for the same inputs.
const CACHE_VERSION: u32 = 1;

/// blake3 of the JSON of everything the image depends on.
fn cache_key(mesh: &TetMesh, optics: &Optics, camera: &Camera) -> [u8; 32] {
    let json = serde_json::json!({
        "version": CACHE_VERSION,
        "mesh": mesh.content_hash(),
        "optics": optics,
        "camera": camera,
        "size": [camera.width, camera.height],
    });
    *blake3::hash(json.to_string().as_bytes()).as_bytes()
}

fn cache_path(dir: &Path, key: &[u8; 32]) -> PathBuf {
    let hex: String = key[..16].iter().map(|b| format!("{b:02x}")).collect();
    dir.join(format!("{hex}.tbref"))
}

/// Reads a cached image; any mismatch (magic, key, size, length, checksum) gives `None`.
fn read_cache(path: &Path, key: &[u8; 32], w: u32, h: u32) -> Option<Image> {
    let bytes = std::fs::read(path).ok()?;
    let n = (w as usize) * (h as usize) * 16;
    let header = 8 + 32 + 8;
    if bytes.len() != header + n + 32 || &bytes[..8] != CACHE_MAGIC || &bytes[8..40] != key {
        return None;
    }
    let (fw, fh) = (
        u32::from_le_bytes(bytes[40..44].try_into().ok()?),
        u32::from_le_bytes(bytes[44..48].try_into().ok()?),
    );
    if (fw, fh) != (w, h) {
        return None;
    }
    let payload = &bytes[header..header + n];
    if blake3::hash(payload).as_bytes() != &bytes[header + n..] {
        return None;
    }
    let pixels = payload
        .chunks_exact(16)
        .map(|c| {
            std::array::from_fn(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap()))
        })
        .collect::<Vec<[f32; 4]>>();
    if pixels.iter().flatten().any(|v| !v.is_finite()) {
        return None;
    }
    Some(Image {
        width: w,
        height: h,
        pixels,
    })
}

fn write_cache(path: &Path, key: &[u8; 32], img: &Image) -> anyhow::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(|e| {
        anyhow::anyhow!(
            "cannot create reference cache directory {}: {e}",
            dir.display()
        )
    })?;
    let mut payload = Vec::with_capacity(img.pixels.len() * 16);
    for p in &img.pixels {
        for v in p {
            payload.extend_from_slice(&v.to_le_bytes());
        }
    }
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    let write = || -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(CACHE_MAGIC)?;
        f.write_all(key)?;
        f.write_all(&img.width.to_le_bytes())?;
        f.write_all(&img.height.to_le_bytes())?;
        f.write_all(&payload)?;
        f.write_all(blake3::hash(&payload).as_bytes())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    };
    write().map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        anyhow::anyhow!("cannot write reference cache file {}: {e}", path.display())
    })
}

/// The reference image, from `cache_dir` when a valid file for exactly this mesh (content
/// hash), camera, optics and size exists; otherwise rendered and stored. Damaged or
/// mismatched files are re-rendered and replaced, never trusted.
pub fn render_cached(
    mesh: &TetMesh,
    optics: &Optics,
    camera: &Camera,
    cache_dir: &Path,
) -> anyhow::Result<Image> {
    let key = cache_key(mesh, optics, camera);
    let path = cache_path(cache_dir, &key);
    if let Some(img) = read_cache(&path, &key, camera.width, camera.height) {
        return Ok(img);
    }
    let img = render(mesh, optics, camera);
    write_cache(&path, &key, &img)?;
    Ok(img)
}

/// The cached reference image for these inputs, if a valid one exists (nothing is rendered).
pub fn read_cached(
    mesh: &TetMesh,
    optics: &Optics,
    camera: &Camera,
    cache_dir: &Path,
) -> Option<Image> {
    let key = cache_key(mesh, optics, camera);
    read_cache(
        &cache_path(cache_dir, &key),
        &key,
        camera.width,
        camera.height,
    )
}

/// Where [`render_cached`] keeps the image for these inputs.
pub fn cache_file(mesh: &TetMesh, optics: &Optics, camera: &Camera, cache_dir: &Path) -> PathBuf {
    cache_path(cache_dir, &cache_key(mesh, optics, camera))
}

// ---------------------------------------------------------------------------------------------
// Dense sampling (independent brute-force integrator, for tests)
// ---------------------------------------------------------------------------------------------

/// A uniform grid over the mesh bounds listing the tets whose boxes overlap each cell.
struct Locator<'m> {
    mesh: &'m TetMesh,
    min: DVec3,
    cell: DVec3,
    dims: [usize; 3],
    offsets: Vec<u32>,
    tets: Vec<u32>,
}

impl<'m> Locator<'m> {
    fn new(mesh: &'m TetMesh) -> Locator<'m> {
        let b = mesh.bounds();
        let min = DVec3::from(b.min);
        let ext = DVec3::from(b.extent()).max(DVec3::splat(1e-30));
        let n = (mesh.num_tets() as f64).cbrt().ceil().max(1.0);
        let longest = ext.max_element();
        let dims = [0, 1, 2].map(|a| ((ext[a] / longest * n).ceil() as usize).clamp(1, 256));
        let cell = DVec3::new(
            ext.x / dims[0] as f64,
            ext.y / dims[1] as f64,
            ext.z / dims[2] as f64,
        );
        let ncell = dims[0] * dims[1] * dims[2];
        let range = |t: usize| {
            let p = mesh.tet_points(t).map(DVec3::from);
            let lo = p[0].min(p[1]).min(p[2]).min(p[3]);
            let hi = p[0].max(p[1]).max(p[2]).max(p[3]);
            let c = |x: DVec3| {
                [0, 1, 2].map(|a| {
                    (((x[a] - min[a]) / cell[a]).floor().max(0.0) as usize).min(dims[a] - 1)
                })
            };
            (c(lo), c(hi))
        };
        let mut counts = vec![0u32; ncell + 1];
        for t in 0..mesh.num_tets() {
            let (lo, hi) = range(t);
            for k in lo[2]..=hi[2] {
                for j in lo[1]..=hi[1] {
                    for i in lo[0]..=hi[0] {
                        counts[i + dims[0] * (j + dims[1] * k) + 1] += 1;
                    }
                }
            }
        }
        for i in 1..counts.len() {
            counts[i] += counts[i - 1];
        }
        let mut fill = counts.clone();
        let mut tets = vec![0u32; counts[ncell] as usize];
        for t in 0..mesh.num_tets() {
            let (lo, hi) = range(t);
            for k in lo[2]..=hi[2] {
                for j in lo[1]..=hi[1] {
                    for i in lo[0]..=hi[0] {
                        let c = i + dims[0] * (j + dims[1] * k);
                        tets[fill[c] as usize] = t as u32;
                        fill[c] += 1;
                    }
                }
            }
        }
        Locator {
            mesh,
            min,
            cell,
            dims,
            offsets: counts,
            tets,
        }
    }

    /// The interpolated scalar at `x`, or `None` outside the mesh (barycentric coordinates by
    /// Cramer's rule, tolerance 1e-12).
    fn scalar_at(&self, x: DVec3) -> Option<f64> {
        let mut c = [0usize; 3];
        for a in 0..3 {
            let f = (x[a] - self.min[a]) / self.cell[a];
            if !(f >= -1e-9 && f <= self.dims[a] as f64 + 1e-9) {
                return None;
            }
            c[a] = (f.floor().max(0.0) as usize).min(self.dims[a] - 1);
        }
        let cell = c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2]);
        for &t in &self.tets[self.offsets[cell] as usize..self.offsets[cell + 1] as usize] {
            let p = self.mesh.tet_points(t as usize).map(DVec3::from);
            let (e1, e2, e3, r) = (p[1] - p[0], p[2] - p[0], p[3] - p[0], x - p[0]);
            let det = e1.dot(e2.cross(e3));
            let l1 = r.dot(e2.cross(e3)) / det;
            let l2 = e1.dot(r.cross(e3)) / det;
            let l3 = e1.dot(e2.cross(r)) / det;
            let l0 = 1.0 - l1 - l2 - l3;
            let tol = -1e-12;
            if l0 >= tol && l1 >= tol && l2 >= tol && l3 >= tol {
                let s = self.mesh.tets[t as usize].map(|v| self.mesh.scalars[v as usize] as f64);
                return Some(l0 * s[0] + l1 * s[1] + l2 * s[2] + l3 * s[3]);
            }
        }
        None
    }
}

/// Brute-force integration for tests: each pixel ray is marched in steps of `step_world`
/// through the mesh's bounding box; the scalar is found by point location at each step's
/// midpoint and the ray equation integrated with the midpoint rule (per step, opacity
/// 1 − exp(−κ·h) and colour c·opacity). Where a step enters or leaves the mesh the crossing is
/// found by bisection, so the boundary costs no first-order error; steps that start and end
/// outside are probed at eighths for thin corners of the mesh. Error O(step²).
pub fn dense_sampling(mesh: &TetMesh, optics: &Optics, camera: &Camera, step_world: f64) -> Image {
    let loc = Locator::new(mesh);
    let b = mesh.bounds();
    let pad = 1e-9 * b.diagonal();
    let (bmin, bmax) = (DVec3::from(b.min) - pad, DVec3::from(b.max) + pad);
    let (w, h) = (camera.width, camera.height);
    let mut pixels = vec![[0f32; 4]; (w * h) as usize];
    pixels.par_iter_mut().enumerate().for_each(|(i, px)| {
        let ray = camera.pixel_ray(i as u32 % w, i as u32 / w);
        let (o, d) = (DVec3::from(ray.origin), DVec3::from(ray.dir));
        // Slab test against the bounding box.
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for a in 0..3 {
            if d[a].abs() < 1e-300 {
                if o[a] < bmin[a] || o[a] > bmax[a] {
                    return;
                }
                continue;
            }
            let (ta, tb) = ((bmin[a] - o[a]) / d[a], (bmax[a] - o[a]) / d[a]);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        if !(t1 > t0) {
            return;
        }
        let at = |t: f64| loc.scalar_at(o + d * t);
        let inside = |t: f64| at(t).is_some();
        let mut acc = [0.0f64; 4];
        let add = |ta: f64, tb: f64, acc: &mut [f64; 4]| {
            if let Some(s) = at(0.5 * (ta + tb)) {
                let s = optics.normalise(s);
                let a = 1.0 - (-optics.tf.kappa_at(s) * (tb - ta) / optics.length_unit).exp();
                let c = optics.tf.color_at(s);
                composite_front_to_back(acc, [c[0] * a, c[1] * a, c[2] * a, a]);
            }
        };
        let crossing = |mut lo: f64, mut hi: f64, lo_inside: bool| {
            for _ in 0..60 {
                let m = 0.5 * (lo + hi);
                if inside(m) == lo_inside {
                    lo = m;
                } else {
                    hi = m;
                }
            }
            0.5 * (lo + hi)
        };
        let n = ((t1 - t0) / step_world).ceil().max(1.0) as usize;
        let hstep = (t1 - t0) / n as f64;
        let mut prev_in = inside(t0);
        for k in 0..n {
            let (ta, tb) = (t0 + k as f64 * hstep, t0 + (k + 1) as f64 * hstep);
            let next_in = inside(tb);
            match (prev_in, next_in) {
                (true, true) => add(ta, tb, &mut acc),
                (false, false) => {
                    // A corner of the mesh thinner than a step: probe inside the step, so
                    // pieces longer than an eighth of a step are not missed.
                    if let Some(m) = (1..8)
                        .map(|q| ta + q as f64 * hstep / 8.0)
                        .find(|&t| inside(t))
                    {
                        let (c0, c1) = (crossing(ta, m, false), crossing(m, tb, true));
                        add(c0, c1, &mut acc);
                    }
                }
                (true, false) => {
                    let tc = crossing(ta, tb, true);
                    add(ta, tc, &mut acc);
                }
                (false, true) => {
                    let tc = crossing(ta, tb, false);
                    add(tc, tb, &mut acc);
                }
            }
            prev_in = next_in;
            if acc[3] > OPAQUE {
                break;
            }
        }
        *px = acc.map(|v| v as f32);
    });
    Image {
        width: w,
        height: h,
        pixels,
    }
}
