//! Spherical shells: `shell` and `onion` on the cubed sphere.

use std::f64::consts::PI;

use rayon::prelude::*;

use super::{finish, FieldEval};
use crate::error::ErrorKind;
use crate::TetMesh;

/// Inner and outer radius of the shell.
pub const SHELL_RADII: (f64, f64) = (0.5, 1.0);

/// (n, m): n cells along each edge of the cubed sphere, m radial layers; 36·n²·m tets.
///
/// The cells' shape comes first, the count second: among the (n, m) whose radial size
/// 0.5/m is 1 to 2.5 times the tangential size at mid-radius, 0.75·(π/2)/n (cells a little
/// thicker than wide, so small meshes spend their tets on angular resolution — a curved outer
/// surface and a real cavity — rather than on layers), the one closest to the target. Only when
/// no such pair is within 25 % of the target (never from 1 k tets up) does the count win, with
/// the shape mismatch as a cost. So `shell:10k` is 10×10 cells per cube face × 3 layers =
/// 10,800 tets with 2,400 boundary faces, not 1 cell × 278 layers of slivers.
pub fn shell_cells(target_tets: usize) -> (usize, usize) {
    let t = target_tets as f64;
    let mut best = (1, 1);
    let mut best_cost = f64::INFINITY;
    for n in 1..=2000usize {
        let per_layer = 36.0 * (n * n) as f64;
        if per_layer > 4.0 * t && n > 1 {
            break;
        }
        let m0 = (t / per_layer).max(1.0);
        for m in [m0.floor().max(1.0) as usize, m0.ceil() as usize] {
            let ratio = (0.5 / m as f64) / (0.75 * PI / 2.0 / n as f64);
            let size_err = ((per_layer * m as f64) - t).abs() / t;
            let shape_err = if ratio < 1.0 {
                (1.0 / ratio).ln()
            } else if ratio > 2.5 {
                (ratio / 2.5).ln()
            } else {
                0.0
            };
            // A shape outside the band costs more than any size error up to 25 %.
            let cost = size_err
                + if shape_err > 0.0 {
                    0.25 + shape_err
                } else {
                    0.0
                };
            if cost < best_cost {
                best_cost = cost;
                best = (n, m);
            }
        }
    }
    best
}

/// (1, m) with m = target/36 layers: the `onion` stress case (what `shell` used to generate at
/// 1 k and 10 k tets, before shape came first). Each layer is 0.5/m thick and ≈ 1.2 wide.
pub fn onion_cells(target_tets: usize) -> (usize, usize) {
    (1, ((target_tets as f64 / 36.0).round() as usize).max(1))
}

/// `shell`: hollow sphere. The cube [0,n]³'s surface lattice points are projected to the unit
/// sphere (equiangular cubed-sphere map: each coordinate c ∈ [-1,1] warped by tan(πc/4)),
/// repeated on m+1 radii; each surface quad × radial layer is a hexahedron split into 6 tets
/// by [`hex_six_tets`], whose diagonal rule depends only on global point indices, so cells
/// conform across the cube's face seams as well. 36·n²·m tets for `cells` = (n, m).
pub(super) fn shell_mesh(
    cells: (usize, usize),
    name: &str,
    f: &FieldEval,
) -> Result<TetMesh, ErrorKind> {
    let (n, m) = cells;
    let (r0, r1) = SHELL_RADII;
    let side = n + 1;
    // Dense index of surface lattice points.
    let mut index = vec![u32::MAX; side * side * side];
    let mut surf: Vec<[f64; 3]> = Vec::new();
    for k in 0..side {
        for j in 0..side {
            for i in 0..side {
                if [i, j, k].iter().any(|&c| c == 0 || c == n) {
                    index[i + side * (j + side * k)] = surf.len() as u32;
                    let c = [i, j, k].map(|c| (PI / 4.0 * (2.0 * c as f64 / n as f64 - 1.0)).tan());
                    let l = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
                    surf.push(c.map(|x| x / l));
                }
            }
        }
    }
    let ns = surf.len();
    let points: Vec<[f64; 3]> = (0..(m + 1) * ns)
        .into_par_iter()
        .map(|g| {
            let r = r0 + (r1 - r0) * (g / ns) as f64 / m as f64;
            surf[g % ns].map(|x| x * r)
        })
        .collect();
    // Surface quads: for each axis and side, the n×n quads of that cube face.
    let mut quads: Vec<[u32; 4]> = Vec::with_capacity(6 * n * n);
    for axis in 0..3 {
        for &fixed in &[0, n] {
            for v in 0..n {
                for u in 0..n {
                    let at = |du: usize, dv: usize| {
                        let mut c = [0usize; 3];
                        c[axis] = fixed;
                        c[(axis + 1) % 3] = u + du;
                        c[(axis + 2) % 3] = v + dv;
                        index[c[0] + side * (c[1] + side * c[2])]
                    };
                    quads.push([at(0, 0), at(1, 0), at(1, 1), at(0, 1)]);
                }
            }
        }
    }
    let tets: Vec<[u32; 4]> = (0..m)
        .into_par_iter()
        .flat_map_iter(|l| {
            let mut out = Vec::with_capacity(quads.len() * 6);
            let (b0, b1) = ((l * ns) as u32, ((l + 1) * ns) as u32);
            for q in &quads {
                let hex = [
                    q[0] + b0,
                    q[1] + b0,
                    q[2] + b0,
                    q[3] + b0,
                    q[0] + b1,
                    q[1] + b1,
                    q[2] + b1,
                    q[3] + b1,
                ];
                hex_six_tets(hex, &mut out);
            }
            out
        })
        .collect();
    finish(name, points, f, tets)
}

/// Faces of a VTK-ordered hexahedron (bottom ring 0..3, top ring 4..7 above it).
const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
];

/// Splits a convex hexahedron into exactly 6 tets: a cone from its vertex of smallest global
/// index over the three faces not incident to it, each cut along the diagonal through *its*
/// vertex of smallest global index (Dompierre et al. 1999's rule). The faces incident to the
/// apex are cut through the apex, which is their smallest vertex too, so every face follows
/// the same global rule and neighbouring cells conform. (The readers' split,
/// [`crate::cells::cell_to_tets`], uses the same rule but takes 5 tets when it can; the shell
/// wants a fixed 6 per cell so its size is predictable: 36·n²·m.)
fn hex_six_tets(v: [u32; 8], out: &mut Vec<[u32; 4]>) {
    let apex = (0..8).min_by_key(|&i| v[i]).unwrap_or(0);
    for f in HEX_FACES {
        if f.contains(&apex) {
            continue;
        }
        let q = f.map(|i| v[i]);
        let m = (0..4).min_by_key(|&i| q[i]).unwrap_or(0);
        let a = v[apex];
        if m % 2 == 0 {
            out.push([a, q[0], q[1], q[2]]);
            out.push([a, q[0], q[2], q[3]]);
        } else {
            out.push([a, q[1], q[2], q[3]]);
            out.push([a, q[1], q[3], q[0]]);
        }
    }
}
