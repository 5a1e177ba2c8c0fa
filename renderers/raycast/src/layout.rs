//! The mesh as the GPU sees it: Table 1 of the paper (§3.1), 144 bytes per tet.
//!
//! Per tet three 48-byte records of three 16-byte texels, as the paper's three F32x4 textures:
//!
//! | record | texel 0 | texel 1 | texel 2 |
//! |---|---|---|---|
//! | vertices | v0.xyz, v3.x | v1.xyz, v3.y | v2.xyz, v3.z |
//! | face normals | n0.xyz, n3.x | n1.xyz, n3.y | n2.xyz, n3.z |
//! | neighbours + scalar | a0, a1 | a2, a3 | g.xyz, c |
//!
//! Face `i` is opposite vertex `i` (`datasets::TET_FACES`) with the outward unit normal `n_i`;
//! `v_{3−i}` lies on face `i`, which is the point the paper's Eq. 1 uses. A neighbour `a_i` is two
//! integers, as the paper's (t_u, t_v) texture coordinates: here (layer, index in layer) of a 2D
//! array texture ([`MESH_TEXTURE_WIDTH`] texels a row), whose layers are at most as large as a
//! storage binding (128 MiB on lavapipe, ≈ 932 K tets at 144 B), up to [`MESH_LAYERS`] of them;
//! a ray walks from any tet to any other by following those pairs. The scalar is s(x) = g·x + c
//! (Eq. 2), already normalised
//! to the transfer function's [0, 1].
//!
//! Positions are in object coordinates (OCS): the mesh moved so that its bounding-box centre is
//! the origin, which keeps f32 ray parameters accurate for meshes far from the world origin;
//! the eye is moved the same way, as the paper moves it with the inverse model matrix.

use datasets::{TetMesh, NO_NEIGHBOUR};
use rayon::prelude::*;
use render_core::Optics;

/// Bytes per tet of the layout (the paper's 144).
pub const BYTES_PER_TET: u64 = 144;
/// 16-byte texels per tet.
pub const TEXELS_PER_TET: usize = 9;
/// Most layers of the mesh texture (24 × 932 K = 22 M tets at lavapipe's 128 MiB a layer).
pub const MESH_LAYERS: usize = 24;
/// Most bytes of one mesh texture: llvmpipe refuses larger (a 2.95 GB texture of 20 M tets
/// failed with "Out of Memory"), so a mesh over it is split over several textures, each of
/// whole layers, bound at bindings 1.. ([`mesh_wgsl`]).
pub const MESH_TEXTURE_BYTES: u64 = 1 << 30;

/// WGSL of `textures` mesh textures `mesh0 …` (group 0, bindings 1..) of `layers_per_texture`
/// layers each, and `texel(c, i)`: texel `i` of layer `c` of the whole mesh.
pub fn mesh_wgsl(textures: usize, layers_per_texture: u32) -> String {
    let mut s = String::new();
    for k in 0..textures {
        s += &format!(
            "@group(0) @binding({}) var mesh{k}: texture_2d_array<u32>;\n",
            k + 1
        );
    }
    s += "fn texel(c: u32, i: u32) -> vec4<u32> {\n";
    if textures == 1 {
        s += "    return texel_at(mesh0, c, i);\n}\n";
        return s;
    }
    s += &format!(
        "    let l = c % {layers_per_texture}u;\n    switch c / {layers_per_texture}u {{\n"
    );
    for k in 0..textures {
        if k + 1 == textures {
            s += &format!("        default: {{ return texel_at(mesh{k}, l, i); }}\n");
        } else {
            s += &format!("        case {k}u: {{ return texel_at(mesh{k}, l, i); }}\n");
        }
    }
    s += "    }\n}\n";
    s
}

/// Texels in a row of the mesh texture (`render_core::texel_texture`).
pub const MESH_TEXTURE_WIDTH: u32 = render_core::texel_texture::TEXEL_ROW;

/// Marks "no tet": a boundary face's missing neighbour, a ray that left the mesh.
pub const NONE: u32 = u32::MAX;

/// A tet address: (binding, index inside the binding), the paper's (t_u, t_v).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TetRef {
    pub chunk: u32,
    pub local: u32,
}

impl TetRef {
    pub const NONE: TetRef = TetRef {
        chunk: NONE,
        local: NONE,
    };

    pub fn is_none(self) -> bool {
        self.chunk == NONE
    }
}

/// The packed mesh: one `Vec` of texels per layer of the mesh texture.
#[derive(Debug, Clone)]
pub struct MeshLayout {
    /// Tets per layer (the last one may hold fewer).
    pub tets_per_chunk: u32,
    /// `chunks[c]` holds tets `c·tets_per_chunk ..`, [`TEXELS_PER_TET`] texels each, as u32 bits.
    pub chunks: Vec<Vec<[u32; 4]>>,
    /// The world point that is the OCS origin (bounding-box centre).
    pub origin: [f64; 3],
    /// Longest tet edge (world units): the 3D table's length axis ends there (§2.2).
    pub longest_edge: f64,
    /// Mean tet edge length: the fixed length of the 2D table.
    pub mean_edge: f64,
}

impl MeshLayout {
    /// Address of global tet `t`.
    pub fn tet_ref(&self, t: u32) -> TetRef {
        if t == NO_NEIGHBOUR {
            return TetRef::NONE;
        }
        TetRef {
            chunk: t / self.tets_per_chunk,
            local: t % self.tets_per_chunk,
        }
    }

    /// Global index of an address.
    pub fn global(&self, r: TetRef) -> u32 {
        r.chunk * self.tets_per_chunk + r.local
    }

    /// The nine texels of a tet.
    pub fn texels(&self, r: TetRef) -> &[[u32; 4]] {
        let base = r.local as usize * TEXELS_PER_TET;
        &self.chunks[r.chunk as usize][base..base + TEXELS_PER_TET]
    }

    /// Packs `mesh` into layers of at most `max_layer_bytes` bytes.
    pub fn build(
        mesh: &TetMesh,
        optics: &Optics,
        max_layer_bytes: u64,
    ) -> anyhow::Result<MeshLayout> {
        let n = mesh.num_tets();
        // 2^24 tets per layer at most, so (layer, index) could also pack into one u32.
        let per = (max_layer_bytes / BYTES_PER_TET).clamp(1, 1 << 24);
        let chunks_needed = (n as u64).div_ceil(per).max(1);
        if chunks_needed > MESH_LAYERS as u64 {
            anyhow::bail!(
                "raycast: mesh {} has {n} tets = {} bytes at 144 B/tet, needs {chunks_needed} \
                 texture layers of {max_layer_bytes} bytes, at most {MESH_LAYERS} are bound",
                mesh.name,
                n as u64 * BYTES_PER_TET
            );
        }
        let per = per as u32;
        let b = mesh.bounds();
        let origin = b.center();
        let range = optics.scalar_max - optics.scalar_min;
        let inv_range = if range > 0.0 { 1.0 / range } else { 0.0 };
        let adjacency = mesh.adjacency();
        let tref = |t: u32| -> [u32; 2] {
            if t == NO_NEIGHBOUR {
                [NONE, NONE]
            } else {
                [t / per, t % per]
            }
        };
        // One tet's texels, its longest edge and its mean edge.
        let pack = |t: usize| -> ([[u32; 4]; TEXELS_PER_TET], f64, f64) {
            let p = mesh.tet_points(t);
            let q: [[f64; 3]; 4] = p.map(|v| [0, 1, 2].map(|a| v[a] - origin[a]));
            // Unit outward normals in f64 (the mesh's own are f32; recompute in
            // f64 from the OCS points for the best f32 rounding).
            let nrm: [[f64; 3]; 4] = std::array::from_fn(|f| {
                let [a, bb, c] = datasets::TET_FACES[f];
                let u = sub(q[bb], q[a]);
                let w = sub(q[c], q[a]);
                let x = cross(u, w);
                let l = dot(x, x).sqrt();
                if l > 0.0 {
                    x.map(|v| v / l)
                } else {
                    mesh.tet_face_normals(t)[f].map(|v| v as f64)
                }
            });
            let s = mesh.tets[t]
                .map(|v| (mesh.scalars[v as usize] as f64 - optics.scalar_min) * inv_range);
            let g = datasets::mesh::linear_gradient(q, s);
            let centre = [0, 1, 2].map(|a| 0.25 * (q[0][a] + q[1][a] + q[2][a] + q[3][a]));
            let c = 0.25 * (s[0] + s[1] + s[2] + s[3]) - dot(g, centre);
            let f = |x: f64| (x as f32).to_bits();
            let a = adjacency[t].map(tref);
            let texels = [
                [f(q[0][0]), f(q[0][1]), f(q[0][2]), f(q[3][0])],
                [f(q[1][0]), f(q[1][1]), f(q[1][2]), f(q[3][1])],
                [f(q[2][0]), f(q[2][1]), f(q[2][2]), f(q[3][2])],
                [f(nrm[0][0]), f(nrm[0][1]), f(nrm[0][2]), f(nrm[3][0])],
                [f(nrm[1][0]), f(nrm[1][1]), f(nrm[1][2]), f(nrm[3][1])],
                [f(nrm[2][0]), f(nrm[2][1]), f(nrm[2][2]), f(nrm[3][2])],
                [a[0][0], a[0][1], a[1][0], a[1][1]],
                [a[2][0], a[2][1], a[3][0], a[3][1]],
                [f(g[0]), f(g[1]), f(g[2]), f(c)],
            ];
            let mut longest: f64 = 0.0;
            let mut sum = 0.0;
            for i in 0..4 {
                for j in i + 1..4 {
                    let e = sub(q[i], q[j]);
                    let l = dot(e, e).sqrt();
                    longest = longest.max(l);
                    sum += l;
                }
            }
            (texels, longest, sum / 6.0)
        };
        // Each layer's texels written in place (no whole-mesh intermediate: at 20 M tets
        // one took 3.2 GB beside the 2.9 GB of bindings); the mean edges are summed in tet
        // order, as one sequential pass would.
        let mut chunks: Vec<Vec<[u32; 4]>> = Vec::with_capacity(chunks_needed as usize);
        let mut longest_edge: f64 = 0.0;
        let mut edge_sum = 0.0;
        for c in 0..chunks_needed as usize {
            let start = c * per as usize;
            let count = (n - start).min(per as usize);
            let mut texels = vec![[0u32; 4]; count * TEXELS_PER_TET];
            let edges: Vec<(f64, f64)> = texels
                .par_chunks_mut(TEXELS_PER_TET)
                .enumerate()
                .map(|(i, out)| {
                    let (tet, longest, mean) = pack(start + i);
                    out.copy_from_slice(&tet);
                    (longest, mean)
                })
                .collect();
            for (longest, mean) in edges {
                longest_edge = longest_edge.max(longest);
                edge_sum += mean;
            }
            chunks.push(texels);
        }
        Ok(MeshLayout {
            tets_per_chunk: per,
            chunks,
            origin,
            longest_edge,
            mean_edge: if n > 0 { edge_sum / n as f64 } else { 0.0 },
        })
    }

    /// Bytes of all layers' texels together (144 per tet; the texture pads each layer to whole
    /// rows of the largest).
    pub fn bytes(&self) -> u64 {
        self.chunks.iter().map(|c| c.len() as u64 * 16).sum()
    }

    /// Rows of the mesh texture: every layer has those of the largest.
    pub fn texture_rows(&self) -> u32 {
        let texels = self.chunks.iter().map(Vec::len).max().unwrap_or(0);
        render_core::texel_texture::TexelTexture::rows_for(texels)
    }
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
