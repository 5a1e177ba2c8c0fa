//! The projection classes of a tetrahedron and the 81-entry truth table of Marroquim et al.
//! (2006, §3.2 and Fig. 3), with the CPU twin of the GPU classification pass.
//!
//! # The four sign tests and the table
//!
//! The paper classifies a projected tet with four ternary tests (each −, 0 or +) whose results
//! index an 81-entry table: Wylie et al.'s 14 non-degenerate cases, 24 "class 3" cases (one
//! vertex projects onto an edge of the silhouette) and 12 "class 4" cases (an edge is seen
//! end-on, two vertices project onto the same point); the remaining entries are fully
//! degenerate projections, which are discarded.
//!
//! Our four tests are the signs of the projected (screen-space) signed areas `A_i` of the
//! tet's four faces, face `i` opposite vertex `i`, wound outwards ([`TET_FACES`]). They are
//! cross products of projected edge vectors, like the paper's tests, and they determine the
//! projection completely because the projected areas of a closed surface cancel (`ΣA_i = 0`):
//!
//! * no zero, one face of the odd sign (3:1) — **class 1**: the vertex `k` opposite the odd face
//!   projects inside that face; the silhouette is face `k`'s triangle, fanned around `k`
//!   (3 triangles). 4 faces × 2 signs = 8 cases.
//! * no zero, two faces of each sign (2:2) — **class 2**: faces `i, j` of one sign share the
//!   edge `(k, l)`, faces `k, l` share the edge `(i, j)`; these two edges cross in projection,
//!   the silhouette is the quadrilateral `k, i, l, j`, fanned around the crossing (4 triangles).
//!   C(4,2) = 6 cases. Classes 1 and 2 together are Wylie's 14.
//! * one zero (face `z` edge-on, its three vertices collinear) and the other three of mixed
//!   sign — **class 3**: of face `z`'s vertices, the middle one `m` is the one whose opposite
//!   face has the odd sign (its area is minus the sum of the other two); `m` lies on the
//!   silhouette edge `(a, b)`, and the silhouette `a, z, b` is fanned around `m` (2 triangles).
//!   4 × 6 = 24 cases.
//! * two zeros (faces `p, q` edge-on) and two opposite signs — **class 4**: the edge `(r, s)`
//!   shared by faces `p` and `q` projects to a point; the silhouette is the triangle
//!   `(r ≡ s, p, q)` (1 triangle). C(4,2) × 2 = 12 cases.
//! * everything else (three or four zeros: all points collinear; or all non-zero signs equal,
//!   which the identity `ΣA_i = 0` rules out and only rounding produces) — discarded.
//!
//! The table is generated from these rules by [`build_table`] and uploaded to the GPU as
//! a storage array; tests check it against an independent convex-hull classification.

use datasets::TET_FACES;

/// Relative tolerance of the zero test: `|A_i| ≤ ZERO_AREA_REL · L²` counts as zero, where `L`
/// is the largest extent of the projected points. It lies above f32 rounding of the projection
/// (~1e-7 relative) so that built-on-purpose class 3/4 configurations classify as such, and
/// turns near-degenerate slivers into class 3/4 fans instead of long thin triangles.
pub const ZERO_AREA_REL: f32 = 1e-5;

/// Ternary digit of one test: 0 for −, 1 for 0, 2 for +.
fn digit(area: f64, eps: f64) -> usize {
    if area > eps {
        2
    } else if area < -eps {
        0
    } else {
        1
    }
}

/// Index into the 81-entry table: `Σ digit_i · 3^i` over the four faces.
pub fn table_index_from_signs(signs: [i8; 4]) -> usize {
    signs
        .iter()
        .enumerate()
        .map(|(i, &s)| ((s + 1) as usize) * 3usize.pow(i as u32))
        .sum()
}

/// Table index of four projected face areas with zero tolerance `eps`.
pub fn table_index(areas: [f64; 4], eps: f64) -> usize {
    (0..4)
        .map(|i| digit(areas[i], eps) * 3usize.pow(i as u32))
        .sum()
}

/// One entry of the truth table: the class (0 = discard) and the vertex permutation the
/// pass needs. Packed for the GPU as `class | perm[0] << 8 | perm[1] << 10 | perm[2] << 12 |
/// perm[3] << 14`.
///
/// Meaning of `perm` per class (tet-local vertex indices):
/// * 1: `[k, a, b, c]` — thick vertex `k`, the other point on triangle `(a, b, c)`;
///   fan ring `a, b, c, a`.
/// * 2: `[k, i, l, j]` — thick vertex where edge `(k, l)` crosses edge `(i, j)`;
///   fan ring `k, i, l, j, k`.
/// * 3: `[m, a, z, b]` — thick vertex `m`, the other point on edge `(a, b)`; fan ring `a, z, b`.
/// * 4: `[r, s, p, q]` — thick vertex `r`, the other point `s`; fan ring `p, q`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TableEntry {
    pub class: u8,
    pub perm: [u8; 4],
}

impl TableEntry {
    pub const DISCARD: TableEntry = TableEntry {
        class: 0,
        perm: [0; 4],
    };

    pub fn packed(&self) -> u32 {
        let mut v = self.class as u32;
        for (i, &p) in self.perm.iter().enumerate() {
            v |= (p as u32) << (8 + 2 * i);
        }
        v
    }

    /// Number of fan triangles (0 when discarded).
    pub fn triangles(&self) -> u32 {
        match self.class {
            1 => 3,
            2 => 4,
            3 => 2,
            4 => 1,
            _ => 0,
        }
    }

    /// The fan ring: `ring[t]`, `ring[t + 1]` with the thick vertex form triangle `t`.
    pub fn ring(&self) -> Vec<u8> {
        let p = self.perm;
        match self.class {
            1 => vec![p[1], p[2], p[3], p[1]],
            2 => vec![p[0], p[1], p[2], p[3], p[0]],
            3 => vec![p[1], p[2], p[3]],
            4 => vec![p[2], p[3]],
            _ => vec![],
        }
    }
}

/// The entry for one sign pattern (signs of the projected face areas, −1/0/+1).
pub fn entry_for_signs(signs: [i8; 4]) -> TableEntry {
    let zeros: Vec<usize> = (0..4).filter(|&i| signs[i] == 0).collect();
    let pos: Vec<usize> = (0..4).filter(|&i| signs[i] > 0).collect();
    let neg: Vec<usize> = (0..4).filter(|&i| signs[i] < 0).collect();
    match zeros.len() {
        0 => {
            if pos.len() == 1 || neg.len() == 1 {
                // Class 1: the odd face's opposite vertex projects inside that face.
                let k = if pos.len() == 1 { pos[0] } else { neg[0] };
                let f = TET_FACES[k];
                TableEntry {
                    class: 1,
                    perm: [k as u8, f[0] as u8, f[1] as u8, f[2] as u8],
                }
            } else if pos.len() == 2 {
                // Class 2: edge (k, l) shared by the two positive faces crosses edge (i, j).
                let (i, j) = (pos[0], pos[1]);
                let (k, l) = (neg[0], neg[1]);
                TableEntry {
                    class: 2,
                    perm: [k as u8, i as u8, l as u8, j as u8],
                }
            } else {
                TableEntry::DISCARD
            }
        }
        1 => {
            if pos.is_empty() || neg.is_empty() {
                return TableEntry::DISCARD;
            }
            // Class 3: face z edge-on; its middle vertex m is opposite the odd-signed face.
            let z = zeros[0];
            let m = if pos.len() == 1 { pos[0] } else { neg[0] };
            let others: Vec<usize> = (0..4).filter(|&v| v != z && v != m).collect();
            TableEntry {
                class: 3,
                perm: [m as u8, others[0] as u8, z as u8, others[1] as u8],
            }
        }
        2 => {
            if pos.len() != 1 || neg.len() != 1 {
                return TableEntry::DISCARD;
            }
            // Class 4: faces p, q edge-on; their shared edge (r, s) is seen end-on.
            let (p, q) = (zeros[0], zeros[1]);
            let rs: Vec<usize> = (0..4).filter(|&v| v != p && v != q).collect();
            TableEntry {
                class: 4,
                perm: [rs[0] as u8, rs[1] as u8, p as u8, q as u8],
            }
        }
        _ => TableEntry::DISCARD,
    }
}

/// Generates the 81-entry truth table; entry `Σ (sign_i + 1) · 3^i`.
pub fn build_table() -> [TableEntry; 81] {
    let mut t = [TableEntry::DISCARD; 81];
    for (idx, e) in t.iter_mut().enumerate() {
        let signs = [0, 1, 2, 3].map(|i| ((idx / 3usize.pow(i)) % 3) as i8 - 1);
        *e = entry_for_signs(signs);
    }
    t
}

/// The table packed for the GPU (see [`TableEntry::packed`]).
pub fn packed_table() -> [u32; 81] {
    build_table().map(|e| e.packed())
}

/// Projected signed areas of the four faces (2× the triangle area, counter-clockwise
/// positive in NDC x right / y up) and the zero tolerance, in f32 as the GPU computes them.
pub fn face_areas_f32(q: [[f32; 2]; 4]) -> ([f32; 4], f32) {
    let mut areas = [0.0f32; 4];
    for (i, f) in TET_FACES.iter().enumerate() {
        let (a, b, c) = (q[f[0]], q[f[1]], q[f[2]]);
        areas[i] = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    }
    let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    for p in q {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let ext = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    (areas, ZERO_AREA_REL * ext * ext)
}

/// What pass 1 computes for one tet (the CPU twin of `pass1.wgsl`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TetRecord {
    /// Clip-space position of the thick vertex (the front point of the thick segment).
    pub thick_clip: [f32; 4],
    /// Normalised scalars at the front and back of the thick segment.
    pub s_front: f32,
    pub s_back: f32,
    /// Thickness in units of the transfer function's length (bounding-box diagonal).
    pub thickness: f32,
    /// Packed fan: class in bits 0..3, triangles in 4..7, ring (5 × 2 bits) from bit 8.
    pub fan: u32,
}

impl TetRecord {
    pub fn class(&self) -> u32 {
        self.fan & 7
    }
    pub fn triangles(&self) -> u32 {
        (self.fan >> 4) & 7
    }
    pub fn ring(&self) -> [u32; 5] {
        [0, 1, 2, 3, 4].map(|i| (self.fan >> (8 + 2 * i)) & 3)
    }
}

/// Packs class, triangle count and ring as the GPU does.
pub fn pack_fan(entry: &TableEntry) -> u32 {
    let mut v = entry.class as u32 | entry.triangles() << 4;
    for (i, &r) in entry.ring().iter().enumerate() {
        v |= (r as u32) << (8 + 2 * i);
    }
    v
}

/// Per-frame parameters of pass 1, shared by the CPU twin and the shader uniform.
#[derive(Debug, Clone, Copy)]
pub struct ProjectParams {
    pub view_proj: [[f32; 4]; 4],
    pub eye: [f32; 3],
    pub forward: [f32; 3],
    pub perspective: bool,
    pub scalar_min: f32,
    pub scalar_inv_range: f32,
    pub inv_length_unit: f32,
}

fn mat_mul(m: &[[f32; 4]; 4], p: [f32; 3]) -> [f32; 4] {
    let mut c = [0.0f32; 4];
    for (r, cr) in c.iter_mut().enumerate() {
        *cr = m[0][r] * p[0] + m[1][r] * p[1] + m[2][r] * p[2] + m[3][r];
    }
    c
}

fn lerp3(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t)
}

/// Screen-space parameter `t` along a projected segment → parameter along the 3D segment
/// (perspective-correct: attributes are affine in 1/w).
fn perspective_t(t: f32, wa: f32, wb: f32) -> f32 {
    let a = (1.0 - t) / wa;
    let b = t / wb;
    if a + b == 0.0 {
        t
    } else {
        b / (a + b)
    }
}

/// Sort key of a point as [`render_core::Camera::sort_distance`] defines it (larger is farther).
pub fn sort_distance_f32(params: &ProjectParams, p: [f32; 3]) -> f32 {
    let d = [
        p[0] - params.eye[0],
        p[1] - params.eye[1],
        p[2] - params.eye[2],
    ];
    if params.perspective {
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    } else {
        d[0] * params.forward[0] + d[1] * params.forward[1] + d[2] * params.forward[2]
    }
}

/// The CPU twin of pass 1 for one tet: classification through the table, thick vertex, front
/// and back scalars, thickness, and centroid sort key. Mirrors `pass1.wgsl` operation by
/// operation in f32.
pub fn classify_tet(
    params: &ProjectParams,
    table: &[TableEntry; 81],
    pos: [[f32; 3]; 4],
    scalars: [f32; 4],
) -> (TetRecord, f32) {
    let centroid = [0, 1, 2].map(|a| 0.25 * (pos[0][a] + pos[1][a] + pos[2][a] + pos[3][a]));
    let depth = sort_distance_f32(params, centroid);
    let clip = pos.map(|p| mat_mul(&params.view_proj, p));
    let q = clip.map(|c| [c[0] / c[3], c[1] / c[3]]);
    let s = scalars.map(|v| ((v - params.scalar_min) * params.scalar_inv_range).clamp(0.0, 1.0));
    let (areas, eps) = face_areas_f32(q);
    let idx = table_index(areas.map(|a| a as f64), eps as f64);
    let entry = table[idx];
    let mut rec = TetRecord {
        fan: pack_fan(&entry),
        ..Default::default()
    };
    if entry.class == 0 {
        return (rec, depth);
    }
    let [v0, v1, v2, v3] = entry.perm.map(|v| v as usize);
    let w = clip.map(|c| c[3]);
    // Two points on the thick ray: `pa` (with scalar `sa`) and `pb` (`sb`).
    let (pa, sa, pb, sb) = match entry.class {
        1 => {
            // Barycentric coordinates of q[v0] in triangle (v1, v2, v3), made perspective-correct.
            let (a, b, c) = (q[v1], q[v2], q[v3]);
            let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            let p = q[v0];
            let l1 = ((p[0] - a[0]) * (c[1] - a[1]) - (p[1] - a[1]) * (c[0] - a[0])) / det;
            let l2 = ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / det;
            let l0 = 1.0 - l1 - l2;
            let (m0, m1, m2) = (l0 / w[v1], l1 / w[v2], l2 / w[v3]);
            let sum = m0 + m1 + m2;
            let (m0, m1, m2) = (m0 / sum, m1 / sum, m2 / sum);
            let pt = [0, 1, 2].map(|k| m0 * pos[v1][k] + m1 * pos[v2][k] + m2 * pos[v3][k]);
            let st = m0 * s[v1] + m1 * s[v2] + m2 * s[v3];
            (pos[v0], s[v0], pt, st)
        }
        2 => {
            // Crossing of projected edges (v0, v2) and (v1, v3).
            let (a, b, c, d) = (q[v0], q[v2], q[v1], q[v3]);
            let r = [b[0] - a[0], b[1] - a[1]];
            let u = [d[0] - c[0], d[1] - c[1]];
            let den = r[0] * u[1] - r[1] * u[0];
            let ac = [c[0] - a[0], c[1] - a[1]];
            let t = ((ac[0] * u[1] - ac[1] * u[0]) / den).clamp(0.0, 1.0);
            let v = ((ac[0] * r[1] - ac[1] * r[0]) / den).clamp(0.0, 1.0);
            let t3 = perspective_t(t, w[v0], w[v2]);
            let v3_ = perspective_t(v, w[v1], w[v3]);
            (
                lerp3(pos[v0], pos[v2], t3),
                s[v0] + (s[v2] - s[v0]) * t3,
                lerp3(pos[v1], pos[v3], v3_),
                s[v1] + (s[v3] - s[v1]) * v3_,
            )
        }
        3 => {
            // q[v0] lies on projected edge (v1, v3): its parameter along the edge.
            let (a, b) = (q[v1], q[v3]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let dd = d[0] * d[0] + d[1] * d[1];
            let t = if dd > 0.0 {
                (((q[v0][0] - a[0]) * d[0] + (q[v0][1] - a[1]) * d[1]) / dd).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t3 = perspective_t(t, w[v1], w[v3]);
            (
                pos[v0],
                s[v0],
                lerp3(pos[v1], pos[v3], t3),
                s[v1] + (s[v3] - s[v1]) * t3,
            )
        }
        _ => (pos[v0], s[v0], pos[v1], s[v1]),
    };
    let ca = mat_mul(&params.view_proj, pa);
    let cb = mat_mul(&params.view_proj, pb);
    let (front, back, sf, sbk) = if ca[2] / ca[3] <= cb[2] / cb[3] {
        (ca, cb, sa, sb)
    } else {
        (cb, ca, sb, sa)
    };
    let _ = back;
    let dl = [pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]];
    rec.thick_clip = front;
    rec.s_front = sf;
    rec.s_back = sbk;
    rec.thickness = (dl[0] * dl[0] + dl[1] * dl[1] + dl[2] * dl[2]).sqrt() * params.inv_length_unit;
    (rec, depth)
}

#[cfg(test)]
mod tests {
    use super::*;
    use render_core::{Camera, Projection, Viewpoint};

    /// SplitMix64: a small deterministic generator for test inputs.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        fn unit(&mut self) -> f64 {
            (self.next() >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.unit()
        }
        fn int(&mut self, n: i64) -> i64 {
            (self.next() % (2 * n as u64 + 1)) as i64 - n
        }
    }

    #[test]
    fn table_has_the_papers_case_counts() {
        let t = build_table();
        let count = |c: u8| t.iter().filter(|e| e.class == c).count();
        // Wylie's 14 = 8 class-1 + 6 class-2; then 24 class-3 and 12 class-4 (§3.2).
        assert_eq!(count(1), 8);
        assert_eq!(count(2), 6);
        assert_eq!(count(3), 24);
        assert_eq!(count(4), 12);
        assert_eq!(count(0), 81 - 50);
        for e in t.iter().filter(|e| e.class > 0) {
            let mut p = e.perm;
            p.sort();
            assert_eq!(p, [0, 1, 2, 3]);
        }
        // Packing round-trips.
        for e in t {
            let p = e.packed();
            assert_eq!(p & 7, e.class as u32);
            for i in 0..4 {
                assert_eq!((p >> (8 + 2 * i)) & 3, e.perm[i] as u32);
            }
        }
    }

    /// An independent classification of 4 projected points from their convex hull, with no
    /// reference to face orientations or the table.
    #[derive(Debug, PartialEq)]
    enum Geo {
        /// Vertex `k` strictly inside the triangle of the others.
        Class1 {
            k: usize,
        },
        /// Convex quadrilateral with crossing diagonals (as sorted pairs, sorted).
        Class2 {
            diagonals: [[usize; 2]; 2],
        },
        /// Vertex `m` strictly inside segment (a, b) (sorted); `z` off the line.
        Class3 {
            m: usize,
            ab: [usize; 2],
            z: usize,
        },
        /// Vertices (r, s) (sorted) project onto the same point.
        Class4 {
            rs: [usize; 2],
        },
        Degenerate,
    }

    fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    }

    fn sorted2(a: usize, b: usize) -> [usize; 2] {
        [a.min(b), a.max(b)]
    }

    fn geometric(q: [[f64; 2]; 4]) -> Geo {
        let others = |v: &[usize]| -> Vec<usize> { (0..4).filter(|i| !v.contains(i)).collect() };
        let mut coincident = vec![];
        for i in 0..4 {
            for j in i + 1..4 {
                if q[i] == q[j] {
                    coincident.push([i, j]);
                }
            }
        }
        if coincident.len() == 1 {
            let [r, s] = coincident[0];
            let o = others(&[r, s]);
            return if orient(q[r], q[o[0]], q[o[1]]) != 0.0 {
                Geo::Class4 { rs: [r, s] }
            } else {
                Geo::Degenerate
            };
        }
        if !coincident.is_empty() {
            return Geo::Degenerate;
        }
        for m in 0..4 {
            let o = others(&[m]);
            for (a, b, z) in [(o[0], o[1], o[2]), (o[0], o[2], o[1]), (o[1], o[2], o[0])] {
                let between = (q[m][0] - q[a][0]) * (q[m][0] - q[b][0])
                    + (q[m][1] - q[a][1]) * (q[m][1] - q[b][1])
                    < 0.0;
                if orient(q[a], q[b], q[m]) == 0.0 && between {
                    return if orient(q[a], q[b], q[z]) != 0.0 {
                        Geo::Class3 {
                            m,
                            ab: sorted2(a, b),
                            z,
                        }
                    } else {
                        Geo::Degenerate
                    };
                }
            }
        }
        for k in 0..4 {
            let o = others(&[k]);
            let (a, b, c) = (q[o[0]], q[o[1]], q[o[2]]);
            let s = [orient(a, b, q[k]), orient(b, c, q[k]), orient(c, a, q[k])];
            if s.iter().all(|&x| x > 0.0) || s.iter().all(|&x| x < 0.0) {
                return Geo::Class1 { k };
            }
        }
        for (p, r) in [([0, 1], [2, 3]), ([0, 2], [1, 3]), ([0, 3], [1, 2])] {
            let d1 = orient(q[p[0]], q[p[1]], q[r[0]]) * orient(q[p[0]], q[p[1]], q[r[1]]);
            let d2 = orient(q[r[0]], q[r[1]], q[p[0]]) * orient(q[r[0]], q[r[1]], q[p[1]]);
            if d1 < 0.0 && d2 < 0.0 {
                let mut d = [p, r];
                d.sort();
                return Geo::Class2 { diagonals: d };
            }
        }
        Geo::Degenerate
    }

    /// What the table says, in the terms of [`Geo`].
    fn from_table(table: &[TableEntry; 81], q: [[f64; 2]; 4], eps: f64) -> Geo {
        let mut areas = [0.0; 4];
        for (i, f) in TET_FACES.iter().enumerate() {
            areas[i] = orient(q[f[0]], q[f[1]], q[f[2]]);
        }
        let e = table[table_index(areas, eps)];
        let p = e.perm.map(|v| v as usize);
        match e.class {
            1 => Geo::Class1 { k: p[0] },
            2 => {
                let mut d = [sorted2(p[0], p[2]), sorted2(p[1], p[3])];
                d.sort();
                Geo::Class2 { diagonals: d }
            }
            3 => Geo::Class3 {
                m: p[0],
                ab: sorted2(p[1], p[3]),
                z: p[2],
            },
            4 => Geo::Class4 {
                rs: sorted2(p[0], p[1]),
            },
            _ => Geo::Degenerate,
        }
    }

    #[test]
    fn table_agrees_with_convex_hull_classification_on_random_projections() {
        let table = build_table();
        let mut rng = Rng(7);
        let mut seen = [0usize; 5];
        for _ in 0..200_000 {
            let q = [0; 4].map(|_| [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)]);
            let mut areas = [0.0f64; 4];
            for (i, f) in TET_FACES.iter().enumerate() {
                areas[i] = orient(q[f[0]], q[f[1]], q[f[2]]);
            }
            // General position: no area near zero (there the tolerance decides, tested below).
            if areas.iter().any(|a| a.abs() < 1e-9) {
                continue;
            }
            let g = geometric(q);
            assert_eq!(from_table(&table, q, 0.0), g, "{q:?}");
            seen[match g {
                Geo::Class1 { .. } => 1,
                Geo::Class2 { .. } => 2,
                _ => 0,
            }] += 1;
        }
        assert!(seen[1] > 1000 && seen[2] > 1000, "{seen:?}");
    }

    #[test]
    fn table_agrees_on_built_class3_and_class4_projections() {
        // Integer coordinates keep every area exact, so zero tests are exact too.
        let table = build_table();
        let mut rng = Rng(11);
        let (mut n3, mut n4) = (0, 0);
        for trial in 0..20_000 {
            let mut q = [0; 4].map(|_| [rng.int(50) as f64, rng.int(50) as f64]);
            let perm = {
                let mut p = [0usize, 1, 2, 3];
                for i in (1..4).rev() {
                    p.swap(i, (rng.next() % (i as u64 + 1)) as usize);
                }
                p
            };
            if trial % 2 == 0 {
                // Class 3: vertex perm[0] exactly at the midpoint of edge (perm[1], perm[2]).
                let a = q[perm[1]];
                let (dx, dy) = (rng.int(20) as f64, rng.int(20) as f64);
                q[perm[2]] = [a[0] + 2.0 * dx, a[1] + 2.0 * dy];
                q[perm[0]] = [a[0] + dx, a[1] + dy];
            } else {
                // Class 4: vertex perm[0] exactly onto vertex perm[1].
                q[perm[0]] = q[perm[1]];
            }
            let g = geometric(q);
            let t = from_table(&table, q, 0.0);
            assert_eq!(t, g, "{q:?}");
            match g {
                Geo::Class3 { .. } => n3 += 1,
                Geo::Class4 { .. } => n4 += 1,
                _ => {}
            }
        }
        assert!(n3 > 5000 && n4 > 5000, "{n3} {n4}");
    }

    /// A camera looking at the unit box from a random direction.
    fn random_camera(rng: &mut Rng, perspective: bool) -> Camera {
        let b = datasets::Aabb {
            min: [-1.0; 3],
            max: [1.0; 3],
        };
        let d = [
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        ];
        let proj = if perspective {
            Projection::default()
        } else {
            Projection::Orthographic
        };
        Camera::fit(&b, &Viewpoint::new("r", d), proj, 128, 128)
    }

    fn params_for(cam: &Camera) -> ProjectParams {
        ProjectParams {
            view_proj: cam.view_proj_f32(),
            eye: cam.eye.map(|c| c as f32),
            forward: cam.forward().map(|c| c as f32),
            perspective: cam.is_perspective(),
            scalar_min: 0.0,
            scalar_inv_range: 1.0,
            inv_length_unit: 1.0,
        }
    }

    /// Exact (f64) entry and exit of a ray through a tet by clipping against its face planes;
    /// returns (t_in, t_out) along the unit direction.
    fn clip_ray(p: [[f64; 3]; 4], o: [f64; 3], d: [f64; 3]) -> Option<(f64, f64)> {
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        for (i, f) in TET_FACES.iter().enumerate() {
            let (a, b, c) = (p[f[0]], p[f[1]], p[f[2]]);
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let mut n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            // Orient the normal away from the opposite vertex (outwards).
            let q = p[i];
            if n[0] * (q[0] - a[0]) + n[1] * (q[1] - a[1]) + n[2] * (q[2] - a[2]) > 0.0 {
                n = n.map(|x| -x);
            }
            let den = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
            let num = n[0] * (a[0] - o[0]) + n[1] * (a[1] - o[1]) + n[2] * (a[2] - o[2]);
            if den.abs() < 1e-300 {
                if num < 0.0 {
                    return None;
                }
                continue;
            }
            let t = num / den;
            if den > 0.0 {
                t1 = t1.min(t);
            } else {
                t0 = t0.max(t);
            }
        }
        (t1 >= t0).then_some((t0, t1))
    }

    /// The thick vertex is where the projection is thickest: its thickness and front/back
    /// scalars equal an exact f64 ray clip through the tet along the ray through the thick
    /// vertex's screen position, for random tets from random directions.
    #[test]
    fn twin_thickness_and_scalars_match_exact_ray_clipping() {
        let table = build_table();
        let mut rng = Rng(3);
        let mut checked = 0;
        let mut near_zero = 0;
        for i in 0..20_000 {
            let cam = random_camera(&mut rng, i % 2 == 0);
            let params = params_for(&cam);
            let c = [
                rng.range(-0.5, 0.5),
                rng.range(-0.5, 0.5),
                rng.range(-0.5, 0.5),
            ];
            let pos = [0; 4].map(|_| [0, 1, 2].map(|a| (c[a] + rng.range(-0.3, 0.3)) as f32));
            let s = [0; 4].map(|_| rng.unit() as f32);
            let p64 = pos.map(|p| p.map(|x| x as f64));
            let vol = datasets::mesh::signed_volume6(p64);
            if vol.abs() < 1e-3 {
                continue;
            }
            let (rec, depth) = classify_tet(&params, &table, pos, s);
            let cen = [0, 1, 2].map(|a| p64.iter().map(|p| p[a]).sum::<f64>() / 4.0);
            assert!((depth as f64 - cam.sort_distance(cen)).abs() < 1e-4);
            if rec.class() == 0 {
                continue;
            }
            // Within a few tolerances of zero area the tolerance itself moves the thick vertex
            // (a nearly-class-1/2 tet drawn as class 3/4): exact ray clipping does not apply.
            let ndc = pos.map(|p| {
                let c = mat_mul(&params.view_proj, p);
                [c[0] / c[3], c[1] / c[3]]
            });
            let (areas, eps) = face_areas_f32(ndc);
            if areas.iter().any(|a| a.abs() < 10.0 * eps) {
                near_zero += 1;
                continue;
            }
            let px = [
                (rec.thick_clip[0] / rec.thick_clip[3] + 1.0) as f64 * 0.5 * cam.width as f64,
                (1.0 - rec.thick_clip[1] / rec.thick_clip[3]) as f64 * 0.5 * cam.height as f64,
            ];
            let ray = cam.ray(px[0], px[1]);
            let Some((t0, t1)) = clip_ray(p64, ray.origin, ray.dir) else {
                panic!(
                    "thick vertex ray misses the tet: class {} {pos:?}",
                    rec.class()
                );
            };
            let len = t1 - t0;
            let diam = 0.6 * 3f64.sqrt();
            assert!(
                (rec.thickness as f64 - len).abs() < 2e-3 * diam,
                "class {} thickness {} vs {len}",
                rec.class(),
                rec.thickness
            );
            // Scalars at entry and exit from the exact linear field.
            let g = datasets::mesh::linear_gradient(p64, s.map(|x| x as f64));
            let at = |t: f64| {
                let x = [0, 1, 2].map(|a| ray.origin[a] + ray.dir[a] * t);
                s[0] as f64 + (0..3).map(|a| g[a] * (x[a] - p64[0][a])).sum::<f64>()
            };
            let grad_len = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
            let tol = 2e-3 * (1.0 + grad_len * diam);
            assert!(
                (rec.s_front as f64 - at(t0)).abs() < tol,
                "s_f {} vs {}",
                rec.s_front,
                at(t0)
            );
            assert!(
                (rec.s_back as f64 - at(t1)).abs() < tol,
                "s_b {} vs {}",
                rec.s_back,
                at(t1)
            );
            checked += 1;
        }
        assert!(
            checked > 15_000 && near_zero < checked / 100,
            "{checked} checked, {near_zero} near zero area"
        );
    }
}
