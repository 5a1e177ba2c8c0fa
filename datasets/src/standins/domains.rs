//! The generated domains: a box around a shape (or a plain box), 5 tets per cell, cut at an
//! exact tet count.

use rayon::prelude::*;

use crate::error::ErrorKind;
use crate::generate::{Field, FieldEval};
use crate::grid::grid_ijk;
use crate::volume::hex_cell_tets;
use crate::TetMesh;

/// Shapes of the generated domains (coordinates in the domain box, see [`Shape::extent`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// A box around a flat, faceted (diamond-shaped) aircraft body: F117's class.
    Faceted,
    /// A box around a fuselage, delta wings and a fin: the fighter's class.
    Fighter,
    /// A box around a thin delta plate: the Delta Wing's class.
    Delta,
    /// An elliptic cylinder (a body) with two ellipsoidal cavities (lungs).
    Torso,
    /// A plain box (convex).
    Box,
}

impl Shape {
    /// Half-extents of the domain box.
    fn extent(self) -> [f64; 3] {
        match self {
            Shape::Faceted => [1.0, 0.7, 0.4],
            Shape::Fighter => [1.0, 0.7, 0.45],
            Shape::Delta => [1.0, 0.6, 0.4],
            Shape::Torso => [0.9, 0.55, 1.0],
            Shape::Box => [1.0, 1.0, 1.0],
        }
    }

    /// Whether the cell centred at `p` belongs to the mesh.
    fn solid(self, p: [f64; 3]) -> bool {
        let [x, y, z] = p;
        match self {
            Shape::Faceted => x.abs() / 0.55 + y.abs() / 0.4 + z.abs() / 0.09 >= 1.0,
            Shape::Fighter => {
                let fuselage = (x / 0.6).powi(2) + (y / 0.09).powi(2) + (z / 0.09).powi(2) < 1.0;
                let wing =
                    z.abs() < 0.035 && (-0.25..0.2).contains(&x) && y.abs() < 0.9 * (0.2 - x);
                let fin = y.abs() < 0.03 && (0.3..0.55).contains(&x) && (0.0..0.22).contains(&z);
                !(fuselage || wing || fin)
            }
            Shape::Delta => {
                !(z.abs() < 0.045 && (-0.6..0.5).contains(&x) && y.abs() < 0.42 * (x + 0.6))
            }
            Shape::Torso => {
                let body = (x / 0.9).powi(2) + (y / 0.55).powi(2) < 1.0;
                let lung = |cx: f64| {
                    ((x - cx) / 0.25).powi(2) + (y / 0.3).powi(2) + ((z - 0.2) / 0.5).powi(2) < 1.0
                };
                body && !lung(-0.38) && !lung(0.38)
            }
            Shape::Box => true,
        }
    }

    pub fn is_convex(self) -> bool {
        self == Shape::Box
    }
}

/// Number of kept cells of `shape` on an `n`-per-unit grid, and the grid's cell counts.
fn domain_cells(shape: Shape, n: f64) -> ([usize; 3], Vec<[usize; 3]>) {
    let ext = shape.extent();
    let cells: [usize; 3] = std::array::from_fn(|a| ((2.0 * ext[a] * n).round() as usize).max(1));
    let kept: Vec<[usize; 3]> = (0..cells[2])
        .into_par_iter()
        .flat_map_iter(|k| {
            let mut out = vec![];
            for j in 0..cells[1] {
                for i in 0..cells[0] {
                    let ijk = [i, j, k];
                    let c = std::array::from_fn(|a| {
                        -ext[a] + 2.0 * ext[a] * (ijk[a] as f64 + 0.5) / cells[a] as f64
                    });
                    if shape.solid(c) {
                        out.push(ijk);
                    }
                }
            }
            out
        })
        .collect();
    (cells, kept)
}

/// A structured domain of `shape`, 5 tets per cell ([`hex_cell_tets`]), with exactly `target`
/// tets: the grid is the smallest (in steps of 1 %) whose kept cells give at least `target`
/// tets, and the tets are taken layer by layer in z until the count is reached, so only the
/// top layer is partly filled. Unused points are dropped; the field is seeded blobs.
pub fn domain_mesh(shape: Shape, target: usize, seed: u64) -> Result<TetMesh, ErrorKind> {
    let ext = shape.extent();
    let volume: f64 = ext.iter().map(|e| 2.0 * e).product();
    let (_, probe) = domain_cells(shape, 12.0);
    let probe_cells: f64 = ext
        .iter()
        .map(|e| (2.0 * e * 12.0).round().max(1.0))
        .product();
    let frac = (probe.len() as f64 / probe_cells).max(1e-3);
    let mut n = (target as f64 / 5.0 / frac / volume).cbrt();
    let (cells, kept) = loop {
        let (cells, kept) = domain_cells(shape, n);
        if kept.len() * 5 >= target {
            break (cells, kept);
        }
        n *= 1.01;
    };
    let d = cells.map(|c| c + 1);
    let mut tets: Vec<[u32; 4]> = Vec::with_capacity(target);
    for c in &kept {
        let five = hex_cell_tets(d, c[0], c[1], c[2]);
        let take = (target - tets.len()).min(5);
        tets.extend_from_slice(&five[..take]);
        if tets.len() == target {
            break;
        }
    }
    let mut remap = vec![u32::MAX; d.iter().product()];
    let mut points: Vec<[f32; 3]> = vec![];
    for t in tets.iter_mut() {
        for v in t.iter_mut() {
            let g = *v as usize;
            if remap[g] == u32::MAX {
                remap[g] = points.len() as u32;
                let ijk = grid_ijk(g, d);
                points.push(std::array::from_fn(|a| {
                    (-ext[a] + 2.0 * ext[a] * ijk[a] as f64 / cells[a] as f64) as f32
                }));
            }
            *v = remap[g];
        }
    }
    let field = FieldEval::new(Field::Blobs, seed);
    let scalars: Vec<f32> = points
        .par_iter()
        .map(|p| field.eval(std::array::from_fn(|a| p[a] as f64 / ext[a])) as f32)
        .collect();
    TetMesh::new("standin", points, scalars, field.name(), tets)
}
