//! Structured boxes: `box`, `slivers` and `tunnels`.

use rayon::prelude::*;

use super::field::rand01;
use super::{finish, FieldEval};
use crate::error::ErrorKind;
use crate::grid::grid_ijk;
use crate::volume::structured_tets;
use crate::TetMesh;

/// Cell counts (a, b, c) with 5·a·b·c as close as possible to `target_tets`, the axes within
/// a factor 2 of each other (cells stay reasonably shaped).
pub fn box_cells(target_tets: usize) -> [usize; 3] {
    let cells = (target_tets as f64 / 5.0).max(1.0);
    let c0 = cells.cbrt().round().max(1.0) as usize;
    let mut best = [c0; 3];
    let mut best_err = f64::INFINITY;
    for a in c0.saturating_sub(3).max(1)..=c0 + 3 {
        for b in a..=a + 3 {
            let c = ((cells / (a * b) as f64).round() as usize).max(b);
            if (c as f64) > 2.0 * a as f64 && a > 2 {
                continue;
            }
            let err = ((a * b * c) as f64 - cells).abs() + 1e-6 * (c - a) as f64;
            if err < best_err {
                best_err = err;
                best = [a, b, c];
            }
        }
    }
    best
}

/// Points of a regular grid with `cells` cells spanning [-1,1]³ (x fastest).
fn grid_points(cells: [usize; 3], z_levels: Option<&[f64]>) -> Vec<[f64; 3]> {
    let d = cells.map(|c| c + 1);
    let n = d[0] * d[1] * d[2];
    (0..n)
        .into_par_iter()
        .map(|g| {
            let ijk = grid_ijk(g, d);
            let mut p = [0, 1, 2].map(|a| -1.0 + 2.0 * ijk[a] as f64 / cells[a] as f64);
            if let Some(z) = z_levels {
                p[2] = z[ijk[2]];
            }
            p
        })
        .collect()
}

/// `box`: 5·a·b·c tets with (a, b, c) = [`box_cells`]`(target)`.
pub(super) fn box_mesh(target: usize, f: &FieldEval) -> Result<TetMesh, ErrorKind> {
    let cells = box_cells(target);
    let points = grid_points(cells, None);
    finish("box", points, f, structured_tets(cells.map(|c| c + 1)))
}

/// Layer thicknesses of the `slivers` mesh: each layer is thin (0.5–4 % of a cell) with
/// probability ½.
fn sliver_z_levels(nz: usize, seed: u64) -> Vec<f64> {
    let t: Vec<f64> = (0..nz)
        .map(|l| {
            if rand01(seed, 7, l as u64) < 0.5 {
                0.005 + 0.035 * rand01(seed, 8, l as u64)
            } else {
                1.0
            }
        })
        .collect();
    let total: f64 = t.iter().sum();
    let mut z = Vec::with_capacity(nz + 1);
    let mut acc = 0.0;
    z.push(-1.0);
    for th in &t {
        acc += th;
        z.push(-1.0 + 2.0 * acc / total);
    }
    z[nz] = 1.0;
    z
}

/// `slivers`: a structured box (5·a·b·c tets, as `box`) whose z layers are thin at random and
/// whose interior points are jittered in x and y by up to 15 % of a cell. The tets of a thin
/// layer are flat (height 0.5–4 % of their width: aspect ratios ≈ 10–100, the "slivers" that
/// make HAVS' k-buffer overflow, Callahan et al. 2005 §4). Validity: a jitter below ¼ of the
/// smallest altitude of a cell's triangles cannot flip any of the 5 tets (their orientation
/// only depends on the x-y triangles between two z levels), so every tet keeps positive volume
/// and the grid stays conforming.
pub(super) fn slivers_mesh(target: usize, f: &FieldEval, seed: u64) -> Result<TetMesh, ErrorKind> {
    let cells = box_cells(target);
    let z = sliver_z_levels(cells[2], seed);
    let mut points = grid_points(cells, Some(&z));
    let d = cells.map(|c| c + 1);
    let h = [2.0 / cells[0] as f64, 2.0 / cells[1] as f64];
    let amp = 0.15 * h[0].min(h[1]);
    points.par_iter_mut().enumerate().for_each(|(g, p)| {
        let (i, j) = (g % d[0], (g / d[0]) % d[1]);
        if i > 0 && i < cells[0] {
            p[0] += amp * (2.0 * rand01(seed, 11, g as u64) - 1.0);
        }
        if j > 0 && j < cells[1] {
            p[1] += amp * (2.0 * rand01(seed, 12, g as u64) - 1.0);
        }
    });
    finish("slivers", points, f, structured_tets(d))
}

/// Tunnels of the `tunnels` mesh: square holes of half-width 1/8 through the cube along each
/// axis, at the four positions (±0.45, ±0.45) of the other two coordinates. A cell is cut
/// away when its centre lies within the half-width of a tunnel's axis line — or, on grids
/// coarser than the tunnels (cells wider than 1/4, below ≈ 2 k tets), within half a cell, so
/// that the cells the line runs through are removed and every tunnel stays open at every size.
fn in_tunnel(c: [f64; 3], cell: [f64; 3]) -> bool {
    const HALF: f64 = 0.125;
    const POS: [f64; 2] = [-0.45, 0.45];
    (0..3).any(|axis| {
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        let near = |x: f64, p: f64, h: f64| (x - p).abs() < HALF.max(0.5 * h);
        POS.iter().any(|&pu| near(c[a], pu, cell[a]))
            && POS.iter().any(|&pv| near(c[b], pv, cell[b]))
    })
}

/// The tunnels' axis lines: (axis, u, v) with u, v the other two coordinates in axis order.
pub const TUNNEL_LINES: [(usize, f64, f64); 12] = {
    let mut out = [(0, 0.0, 0.0); 12];
    let pos = [-0.45, 0.45];
    let mut i = 0;
    while i < 12 {
        out[i] = (i / 4, pos[(i / 2) % 2], pos[i % 2]);
        i += 1;
    }
    out
};

fn cell_size(cells: [usize; 3]) -> [f64; 3] {
    cells.map(|c| 2.0 / c as f64)
}

/// Number of cells outside the tunnels.
fn tunnel_kept(cells: [usize; 3]) -> usize {
    let h = cell_size(cells);
    (0..cells[2])
        .into_par_iter()
        .map(|k| {
            let mut kept = 0;
            for j in 0..cells[1] {
                for i in 0..cells[0] {
                    if !in_tunnel(cell_center(cells, i, j, k), h) {
                        kept += 1;
                    }
                }
            }
            kept
        })
        .sum()
}

fn cell_center(cells: [usize; 3], i: usize, j: usize, k: usize) -> [f64; 3] {
    let ijk = [i, j, k];
    [0, 1, 2].map(|a| -1.0 + 2.0 * (ijk[a] as f64 + 0.5) / cells[a] as f64)
}

/// `tunnels`: a structured box with the cells inside the tunnels removed (whole cells, so the
/// remaining 5-tet splits still conform); unused points are dropped. A ray along an axis at
/// (±0.45, 0) of the other coordinates passes 2 tunnels: 6 boundary crossings.
pub(super) fn tunnels_mesh(target: usize, f: &FieldEval) -> Result<TetMesh, ErrorKind> {
    // About 0.59 of the cells are kept: size the box so the kept cells hit the target, then
    // correct once with the measured fraction.
    let mut cells = box_cells((target as f64 / 0.59) as usize);
    let kept = tunnel_kept(cells);
    if kept > 0 {
        let frac = kept as f64 / cells.iter().product::<usize>() as f64;
        cells = box_cells((target as f64 / frac) as usize);
    }
    let d = cells.map(|c| c + 1);
    let mut tets = Vec::new();
    for k in 0..cells[2] {
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                if !in_tunnel(cell_center(cells, i, j, k), cell_size(cells)) {
                    tets.extend_from_slice(&crate::volume::hex_cell_tets(d, i, j, k));
                }
            }
        }
    }
    let all = grid_points(cells, None);
    // Compact: keep only points used by some tet.
    let mut remap = vec![u32::MAX; all.len()];
    for t in &tets {
        for &v in t {
            remap[v as usize] = 0;
        }
    }
    let mut points = Vec::new();
    for (g, r) in remap.iter_mut().enumerate() {
        if *r == 0 {
            *r = points.len() as u32;
            points.push(all[g]);
        }
    }
    tets.par_iter_mut()
        .for_each(|t| *t = t.map(|v| remap[v as usize]));
    finish("tunnels", points, f, tets)
}
