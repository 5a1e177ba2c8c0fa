//! A CPU model of HAVS' image space: the sorted faces rasterised into an exact A-buffer (every
//! fragment of every pixel, in arrival order, with its exact depth along the pixel's ray).
//!
//! It answers the paper's §5.2 / Table 2 questions — how many fragments, how long the
//! per-pixel lists get, and how large k must be for the k-buffer to complete the sort exactly
//! ([`kbuffer_stats`], Fig. 6's maps) — and, streamed through the k-buffer twin, gives the
//! image the race-free GPU mode must produce ([`model_image`]).
//!
//! Rasterisation samples pixel centres with a top-left rule, as GPUs do, so a pixel centre on
//! an edge shared by two faces belongs to one of them. Rows are split into bands processed in
//! parallel (rayon); each band walks all faces in order, so arrival order is preserved.

use rayon::prelude::*;
use render_core::preintegration::Table3d;
use render_core::sort::{radix_sort_indices, RadixScratch};
use render_core::{Camera, Image};

use crate::kbuffer::{
    composite_front_to_back, Fragment, KBuffer, Tag, TagScheme, EARLY_TERMINATION_ALPHA,
};

/// The vertices HAVS draws (xyz, normalised scalar + 2 on boundary copies) and its unique
/// faces as indices into them; see [`crate::tagged_geometry`].
#[derive(Debug, Clone)]
pub struct Geometry {
    pub verts: Vec<[f32; 4]>,
    pub faces: Vec<[u32; 3]>,
}

impl Geometry {
    /// Face indices front to back by centroid distance (HAVS §5.1), with the same f32 keys and
    /// radix sort as the renderer's CPU path.
    pub fn face_order(&self, camera: &Camera) -> Vec<u32> {
        let eye = camera.eye.map(|c| c as f32);
        let fwd = camera.forward().map(|c| c as f32);
        let persp = camera.is_perspective();
        let keys: Vec<f32> = self
            .faces
            .par_iter()
            .map(|f| {
                let p = f.map(|v| self.verts[v as usize]);
                let c = [0, 1, 2].map(|a| (p[0][a] + p[1][a] + p[2][a]) / 3.0);
                crate::sort_key(eye, fwd, persp, c)
            })
            .collect();
        let mut order = Vec::new();
        radix_sort_indices(&keys, &mut order, &mut RadixScratch::default());
        order
    }
}

/// One fragment of the A-buffer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AFrag {
    /// Distance along the pixel's ray (world units; along the view direction for orthographic).
    pub depth: f32,
    pub scalar: f32,
    pub tag: Tag,
}

impl AFrag {
    pub fn fragment(&self) -> Fragment {
        Fragment {
            scalar: self.scalar,
            depth: self.depth,
            tag: self.tag,
        }
    }
}

/// The per-pixel fragment lists of a band of rows, each list in arrival order.
pub struct Band {
    pub y0: u32,
    pub rows: u32,
    pub width: u32,
    /// `offsets[i]..offsets[i + 1]` are pixel i's fragments (i = local row · width + x).
    pub offsets: Vec<u32>,
    pub frags: Vec<AFrag>,
}

impl Band {
    pub fn list(&self, i: usize) -> &[AFrag] {
        &self.frags[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
    pub fn pixels(&self) -> usize {
        self.offsets.len() - 1
    }
}

struct ProjectedFace {
    /// Screen positions (pixels, y down).
    s: [[f64; 2]; 3],
    /// Plane of the face in world space: unit normal (wound as the face) and a point.
    n: [f64; 3],
    a: [f64; 3],
    p: [[f64; 3]; 3],
    v: [f32; 3],
    boundary: bool,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Whether an edge with direction (dx, dy) (interior on its positive side) owns the pixel
/// centres lying exactly on it. Of an edge and its reverse exactly one does.
fn owns_edge(dx: f64, dy: f64) -> bool {
    dy > 0.0 || (dy == 0.0 && dx < 0.0)
}

/// Rasterises the faces in `order` into per-pixel lists, band by band in parallel, and maps
/// each band with `f`.
pub fn for_each_band<R: Send>(
    geom: &Geometry,
    order: &[u32],
    camera: &Camera,
    band_rows: u32,
    f: impl Fn(&Band) -> R + Sync,
) -> Vec<R> {
    let (w, h) = (camera.width, camera.height);
    let faces = project_faces(geom, order, camera);
    let view = View {
        width: w,
        rays: (0..w * h)
            .into_par_iter()
            .map(|i| {
                let r = camera.pixel_ray(i % w, i / w);
                (r.origin, r.dir)
            })
            .collect(),
        eye: camera.eye,
        forward: camera.forward(),
        perspective: camera.is_perspective(),
    };
    let bands: Vec<u32> = (0..h.div_ceil(band_rows)).collect();
    bands
        .par_iter()
        .map(|&b| {
            let y0 = b * band_rows;
            let y1 = (y0 + band_rows).min(h);
            let mut raw: Vec<(u32, AFrag)> = Vec::new();
            for face in &faces {
                rasterise(face, &view, y0..y1, &mut raw);
            }
            let (offsets, frags) = by_pixel(raw, ((y1 - y0) * w) as usize);
            f(&Band {
                y0,
                rows: y1 - y0,
                width: w,
                offsets,
                frags,
            })
        })
        .collect()
}

/// The faces in `order`, projected to the screen with their planes and scalars.
fn project_faces(geom: &Geometry, order: &[u32], camera: &Camera) -> Vec<ProjectedFace> {
    let (w, h) = (camera.width as f64, camera.height as f64);
    let vp = camera.view_proj();
    let screen: Vec<[f64; 2]> = geom
        .verts
        .par_iter()
        .map(|p| {
            let c = vp * glam::DVec4::new(p[0] as f64, p[1] as f64, p[2] as f64, 1.0);
            let ndc = c.truncate() / c.w;
            [(ndc.x + 1.0) * 0.5 * w, (1.0 - ndc.y) * 0.5 * h]
        })
        .collect();
    order
        .par_iter()
        .map(|&fi| {
            let f = geom.faces[fi as usize];
            let p = f.map(|v| {
                let q = geom.verts[v as usize];
                [q[0] as f64, q[1] as f64, q[2] as f64]
            });
            let n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
            let l = dot(n, n).sqrt().max(f64::MIN_POSITIVE);
            let v = f.map(|v| geom.verts[v as usize][3]);
            ProjectedFace {
                s: f.map(|v| screen[v as usize]),
                n: n.map(|x| x / l),
                a: p[0],
                p,
                v,
                boundary: v[0] >= 1.5,
            }
        })
        .collect()
}

/// What rasterising needs of the camera: every pixel's ray, the eye and the view direction.
struct View {
    width: u32,
    rays: Vec<([f64; 3], [f64; 3])>,
    eye: [f64; 3],
    forward: [f64; 3],
    perspective: bool,
}

/// Appends the fragments of `face` in rows `rows` to `out`, as (pixel within the rows,
/// fragment), pixel centres sampled with the top-left rule.
fn rasterise(
    face: &ProjectedFace,
    view: &View,
    rows: std::ops::Range<u32>,
    out: &mut Vec<(u32, AFrag)>,
) {
    let w = view.width;
    let [a, bb, c] = face.s;
    let area = (bb[0] - a[0]) * (c[1] - a[1]) - (bb[1] - a[1]) * (c[0] - a[0]);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    // Order the corners so the interior is on the positive side of each edge.
    let (a, bb, c) = if area > 0.0 { (a, bb, c) } else { (a, c, bb) };
    let ymin = a[1].min(bb[1]).min(c[1]);
    let ymax = a[1].max(bb[1]).max(c[1]);
    let py0 = ((ymin - 0.5).ceil().max(rows.start as f64)) as i64;
    let py1 = ((ymax - 0.5).floor().min(rows.end as f64 - 1.0)) as i64;
    if py0 > py1 {
        return;
    }
    let xmin = a[0].min(bb[0]).min(c[0]);
    let xmax = a[0].max(bb[0]).max(c[0]);
    let px0 = ((xmin - 0.5).ceil().max(0.0)) as i64;
    let px1 = ((xmax - 0.5).floor().min(w as f64 - 1.0)) as i64;
    if px0 > px1 {
        return;
    }
    let edges = [(a, bb), (bb, c), (c, a)];
    for py in py0..=py1 {
        let y = py as f64 + 0.5;
        for px in px0..=px1 {
            let x = px as f64 + 0.5;
            let inside = edges.iter().all(|&(p, q)| {
                let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
                let e = dx * (y - p[1]) - dy * (x - p[0]);
                e > 0.0 || (e == 0.0 && owns_edge(dx, dy))
            });
            if !inside {
                continue;
            }
            let ray = view.rays[(py as u32 * w + px as u32) as usize];
            if let Some(frag) = fragment(face, view, ray) {
                out.push(((py as u32 - rows.start) * w + px as u32, frag));
            }
        }
    }
}

/// The fragment where `ray` (origin, direction) meets `face`'s plane: its depth, its scalar
/// interpolated with barycentric weights, and its tag (boundary faces are wound outward, so a
/// ray seen from outside enters); none for a ray parallel to the plane.
fn fragment(face: &ProjectedFace, view: &View, (o, d): ([f64; 3], [f64; 3])) -> Option<AFrag> {
    let nd = dot(face.n, d);
    if nd == 0.0 {
        return None;
    }
    let t = dot(face.n, sub(face.a, o)) / nd;
    let hit = [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]];
    let depth = if view.perspective {
        t
    } else {
        dot(sub(hit, view.eye), view.forward)
    };
    // Barycentric weights of the hit point in the face's plane.
    let [p0, p1, p2] = face.p;
    let w0 = dot(cross(sub(p1, hit), sub(p2, hit)), face.n);
    let w1 = dot(cross(sub(p2, hit), sub(p0, hit)), face.n);
    let w2 = dot(cross(sub(p0, hit), sub(p1, hit)), face.n);
    let sum = w0 + w1 + w2;
    let raw_v = if sum != 0.0 {
        (w0 * face.v[0] as f64 + w1 * face.v[1] as f64 + w2 * face.v[2] as f64) / sum
    } else {
        face.v[0] as f64
    };
    let (scalar, tag) = if face.boundary {
        (
            (raw_v - 2.0).clamp(0.0, 1.0),
            if nd < 0.0 { Tag::Entry } else { Tag::Exit },
        )
    } else {
        (raw_v.clamp(0.0, 1.0), Tag::Interior)
    };
    Some(AFrag {
        depth: depth as f32,
        scalar: scalar as f32,
        tag,
    })
}

/// `raw` (pixel, fragment) pairs as per-pixel lists over `npx` pixels: a counting sort by
/// pixel, which keeps each pixel's fragments in arrival order. Returns the lists' offsets and
/// the fragments.
fn by_pixel(raw: Vec<(u32, AFrag)>, npx: usize) -> (Vec<u32>, Vec<AFrag>) {
    let mut offsets = vec![0u32; npx + 1];
    for (p, _) in &raw {
        offsets[*p as usize + 1] += 1;
    }
    for i in 0..npx {
        offsets[i + 1] += offsets[i];
    }
    let mut fill = offsets.clone();
    let mut frags = vec![
        AFrag {
            depth: 0.0,
            scalar: 0.0,
            tag: Tag::Interior
        };
        raw.len()
    ];
    for (p, fr) in raw {
        let slot = &mut fill[p as usize];
        frags[*slot as usize] = fr;
        *slot += 1;
    }
    (offsets, frags)
}

/// Table 2's figures for one view, and Fig. 6's map of where small k-buffers fail.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KStats {
    pub fragments: u64,
    /// Longest per-pixel list (the A-buffer depth).
    pub max_list: u32,
    /// Largest k any pixel needs, as the paper measures it: the deepest insertion into an
    /// ordered A-buffer, plus one ([`crate::kbuffer::insertion_k`], §5.2).
    pub max_k: u32,
    /// Pixels whose k (the paper's measure) exceeds 2 and 6, the hardware's k values.
    pub pixels_k_gt2: u64,
    pub pixels_k_gt6: u64,
    /// The same with the exact minimum k of our k-buffer twin ([`crate::kbuffer::k_needed`]),
    /// never above the paper's measure: what the race-free renderer actually needs.
    pub exact_max_k: u32,
    pub exact_pixels_k_gt2: u64,
    pub exact_pixels_k_gt6: u64,
    pub covered_pixels: u64,
    /// Per pixel (row 0 at the top): its k, the paper's measure (0 where no fragment),
    /// saturated at 255.
    pub k_map: Vec<u8>,
    pub width: u32,
    pub height: u32,
}

/// Rasterises the sorted faces at the camera's resolution and measures, per pixel, how far out
/// of order its fragments arrive, by the paper's insertion depth ([`crate::kbuffer::insertion_k`])
/// and by the exact minimum of our k-buffer ([`crate::kbuffer::k_needed`]).
pub fn kbuffer_stats(geom: &Geometry, camera: &Camera) -> KStats {
    let order = geom.face_order(camera);
    let bands = for_each_band(geom, &order, camera, 16, |band| {
        let mut s = KStats::default();
        let mut map = vec![0u8; band.pixels()];
        let mut depths = Vec::new();
        for (i, m) in map.iter_mut().enumerate() {
            let list = band.list(i);
            if list.is_empty() {
                continue;
            }
            depths.clear();
            depths.extend(list.iter().map(|f| f.depth));
            let k = crate::kbuffer::insertion_k(&depths) as u32;
            let exact = crate::kbuffer::k_needed(&depths) as u32;
            s.exact_max_k = s.exact_max_k.max(exact);
            s.exact_pixels_k_gt2 += (exact > 2) as u64;
            s.exact_pixels_k_gt6 += (exact > 6) as u64;
            s.fragments += list.len() as u64;
            s.max_list = s.max_list.max(list.len() as u32);
            s.max_k = s.max_k.max(k);
            s.pixels_k_gt2 += (k > 2) as u64;
            s.pixels_k_gt6 += (k > 6) as u64;
            s.covered_pixels += 1;
            *m = k.min(255) as u8;
        }
        (s, map)
    });
    let mut total = KStats {
        width: camera.width,
        height: camera.height,
        ..Default::default()
    };
    for (s, map) in bands {
        total.fragments += s.fragments;
        total.max_list = total.max_list.max(s.max_list);
        total.max_k = total.max_k.max(s.max_k);
        total.exact_max_k = total.exact_max_k.max(s.exact_max_k);
        total.exact_pixels_k_gt2 += s.exact_pixels_k_gt2;
        total.exact_pixels_k_gt6 += s.exact_pixels_k_gt6;
        total.pixels_k_gt2 += s.pixels_k_gt2;
        total.pixels_k_gt6 += s.pixels_k_gt6;
        total.covered_pixels += s.covered_pixels;
        total.k_map.extend(map);
    }
    total
}

impl KStats {
    /// Fig. 6 style map: black where no fragment, grey where k ≤ 2 suffices, yellow where
    /// 2 < k ≤ 6 is needed, red where k > 6 is needed.
    pub fn k_map_image(&self) -> image::RgbImage {
        image::RgbImage::from_fn(self.width, self.height, |x, y| {
            let k = self.k_map[(y * self.width + x) as usize];
            image::Rgb(match k {
                0 => [0, 0, 0],
                1 | 2 => [90, 90, 90],
                3..=6 => [255, 210, 0],
                _ => [230, 20, 20],
            })
        })
    }
}

/// What the race-free GPU mode computes, on the CPU: each pixel's fragments in submission
/// order through the k-buffer twin, segments shaded by the table's CPU twin. Returns the image
/// and the number of out-of-order pops.
pub fn model_image(
    geom: &Geometry,
    camera: &Camera,
    table: &Table3d,
    k: usize,
    scheme: TagScheme,
    early_termination: bool,
) -> (Image, u64) {
    let order = geom.face_order(camera);
    let bands = for_each_band(geom, &order, camera, 16, |band| {
        let mut px = vec![[0f32; 4]; band.pixels()];
        let mut errors = 0u64;
        let mut segs = Vec::new();
        for (i, out) in px.iter_mut().enumerate() {
            let mut kb = KBuffer::new(k, scheme);
            let mut acc = [0f32; 4];
            segs.clear();
            let mut stopped = false;
            for f in band.list(i) {
                if early_termination && acc[3] >= EARLY_TERMINATION_ALPHA {
                    stopped = true;
                    break;
                }
                if let Some(s) = kb.insert(f.fragment()) {
                    shade(table, &s, &mut acc);
                }
            }
            if !(stopped || early_termination && acc[3] >= EARLY_TERMINATION_ALPHA) {
                kb.drain(&mut segs);
                for s in &segs {
                    shade(table, s, &mut acc);
                }
            }
            errors += kb.out_of_order as u64;
            *out = acc;
        }
        (px, errors)
    });
    let mut img = Image::new(camera.width, camera.height);
    let mut errors = 0;
    let mut at = 0;
    for (px, e) in bands {
        img.pixels[at..at + px.len()].copy_from_slice(&px);
        at += px.len();
        errors += e;
    }
    (img, errors)
}

fn shade(table: &Table3d, s: &crate::kbuffer::Segment, acc: &mut [f32; 4]) {
    if !s.inside {
        return;
    }
    let c = table.sample(
        s.front.scalar as f64,
        s.back.scalar as f64,
        (s.back.depth - s.front.depth) as f64,
    );
    composite_front_to_back(acc, c.map(|x| x as f32));
}
