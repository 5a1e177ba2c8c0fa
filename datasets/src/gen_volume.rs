//! Generated regular volumes: a smooth analytic field on a voxel grid, as a [`TetMesh`] that
//! carries its grid ([`TetMesh::source_grid`]) so that voxel renderers (`splat`) draw the exact
//! voxels and every tet algorithm and the reference draw the same data as tets.
//!
//! Specs (registry names):
//! * `vol:N` or `vol:NXxNYxNZ` — a sum of seeded compact bumps, normalised to [0, 1], that
//!   fills about half the box; optional `:eff=COUNT` (exactly COUNT voxels above 0, see below)
//!   and `:seed=N`.
//!
//! The stand-ins for Grau & Tost's Table 1 volumes (`lobster` … `stagbeetle`, also spelled
//! `standin:NAME`) live with the other stand-ins in [`crate::standins`].
//!
//! The field is exactly 0 outside the bumps (each bump is (1 − r²/ρ²)³, C² smooth). With
//! `eff=COUNT` the field is shifted down so that exactly the COUNT largest voxels stay above 0:
//! v ← max(v − t, 0) / (1 − t), t the (COUNT+1)-th largest value.
//!
//! The tet mesh splits (5 tets per cell, as [`crate::volume::structured_tets`]) only the cells
//! with at least one non-zero corner. The cells left out hold 0 at all eight corners, so under
//! a transfer function with κ(0) = 0 the mesh renders exactly like the full split; under one
//! with κ(0) > 0 the data set is defined as the support (the `splat` renderer splats only grid
//! points the tets use, so both see the same data). Every grid point stays a mesh point (grid
//! order), unused ones included.

use std::sync::Arc;

use rayon::prelude::*;

use crate::error::{ErrorKind, LoadError};
use crate::grid::grid_ijk;
use crate::volume::{CellSplit, VoxelGrid};
use crate::voxel_volume::{CellCover, VoxelVolume};
use crate::TetMesh;

/// The largest tet split a generated volume may have (16 bytes per tet, plus the checks).
pub const MAX_VOLUME_TETS: usize = 60_000_000;

/// A parsed volume spec.
#[derive(Debug, Clone, PartialEq)]
pub struct VolumeSpec {
    pub dims: [usize; 3],
    /// Exactly this many voxels above 0 (the rest exactly 0).
    pub effective: Option<usize>,
    pub seed: u64,
}

/// Whether `s` names a generated volume (`vol:…`).
pub fn is_volume_spec(s: &str) -> bool {
    let head = s
        .split(':')
        .next()
        .unwrap_or("")
        .trim()
        .to_ascii_lowercase();
    s.contains(':') && head == "vol"
}

fn syntax(expected: &str, found: &str) -> ErrorKind {
    ErrorKind::Syntax {
        expected: expected.into(),
        found: found.into(),
    }
}

/// Parses `vol:64`, `vol:128x96x64:eff=100k:seed=3`.
pub fn parse_volume_spec(spec: &str) -> Result<VolumeSpec, ErrorKind> {
    let mut parts = spec.split(':').map(str::trim);
    parts.next(); // "vol"
    let size = parts.next().unwrap_or("").to_ascii_lowercase();
    let mut out = {
        let dims: Vec<usize> = size
            .split('x')
            .map(|d| d.parse::<usize>().ok().filter(|&d| (2..=4096).contains(&d)))
            .collect::<Option<Vec<_>>>()
            .ok_or_else(|| {
                syntax(
                    "grid points per axis, 2…4096: vol:64 or vol:128x96x64",
                    &size,
                )
            })?;
        let dims = match dims[..] {
            [n] => [n; 3],
            [x, y, z] => [x, y, z],
            _ => return Err(syntax("vol:N or vol:NXxNYxNZ", &size)),
        };
        VolumeSpec {
            dims,
            effective: None,
            seed: 1,
        }
    };
    for opt in parts {
        let (k, v) = opt
            .split_once('=')
            .ok_or_else(|| syntax("an option eff=COUNT or seed=N", opt))?;
        match k.trim() {
            "eff" => {
                out.effective = Some(
                    crate::generate::parse_size(v)
                        .ok_or_else(|| syntax("eff=<voxel count> such as 233k", v))?,
                )
            }
            "seed" => out.seed = v.trim().parse().map_err(|_| syntax("seed=<integer>", v))?,
            _ => return Err(syntax("an option eff=… or seed=…", opt)),
        }
    }
    let n: usize = out.dims.iter().product();
    if let Some(e) = out.effective {
        if e == 0 || e >= n {
            return Err(syntax(
                &format!("eff between 1 and {} (voxels)", n - 1),
                &e.to_string(),
            ));
        }
    }
    Ok(out)
}

/// Counter-based SplitMix64: deterministic per (seed, index).
fn hash01(seed: u64, i: u64) -> f64 {
    let mut z = seed
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(i.wrapping_mul(0xBF58_476D_1CE4_E5B9))
        .wrapping_add(0x94D0_49BB_1331_11EB);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// Bumps of the field, in voxel units: centre, radius, amplitude.
struct Bump {
    c: [f64; 3],
    rho: f64,
    amp: f64,
}

const BUMPS: usize = 12;

/// Bumps whose supports cover about `fill` of the box (overlaps ignored), centres inside it.
fn bumps(dims: [usize; 3], fill: f64, seed: u64) -> Vec<Bump> {
    let n: f64 = dims.iter().map(|&d| d as f64).product();
    let rho = (3.0 * fill * n / (4.0 * std::f64::consts::PI * BUMPS as f64)).cbrt();
    (0..BUMPS)
        .map(|b| {
            let h = |k: u64| hash01(seed, b as u64 * 8 + k);
            Bump {
                // Centres at irrational-looking offsets, so that no symmetry makes equal values.
                c: [0, 1, 2].map(|a| (0.15 + 0.7 * h(a as u64)) * (dims[a] - 1) as f64),
                rho: rho * (0.7 + 0.6 * h(3)),
                amp: 0.5 + 0.5 * h(4),
            }
        })
        .collect()
}

fn field(bumps: &[Bump], p: [f64; 3]) -> f64 {
    bumps
        .iter()
        .map(|b| {
            let r2 = (0..3).map(|a| (p[a] - b.c[a]).powi(2)).sum::<f64>() / (b.rho * b.rho);
            if r2 < 1.0 {
                b.amp * (1.0 - r2).powi(3)
            } else {
                0.0
            }
        })
        .sum()
}

/// The voxel grid of a spec: unit spacing, origin 0, values in [0, 1].
pub fn volume_grid(spec: &VolumeSpec) -> Result<VoxelGrid, ErrorKind> {
    let dims = spec.dims;
    let n: usize = dims.iter().product();
    let want = spec.effective;
    // Enough support that the `want` largest voxels exist; grown if the bumps overlap a lot.
    let mut fill = want.map_or(0.5, |e| (2.5 * e as f64 / n as f64).min(1.0));
    for _ in 0..6 {
        let bs = bumps(dims, fill, spec.seed);
        let mut values: Vec<f32> = (0..n)
            .into_par_iter()
            .map(|g| {
                let p = grid_ijk(g, dims);
                field(&bs, p.map(|c| c as f64)) as f32
            })
            .collect();
        let positive = values.par_iter().filter(|&&v| v > 0.0).count();
        let max = values.par_iter().copied().reduce(|| 0.0, f32::max);
        if max <= 0.0 || want.is_some_and(|e| positive <= e) {
            fill = (fill * 1.6).min(4.0);
            continue;
        }
        let (shift, scale) = match want {
            Some(e) => {
                let mut pos: Vec<f32> = values.par_iter().copied().filter(|&v| v > 0.0).collect();
                // t = the (e+1)-th largest: exactly e values lie above it (no ties in practice).
                let k = pos.len() - 1 - e;
                let (_, t, _) = pos.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
                let t = *t;
                (t, 1.0 / (max - t))
            }
            None => (0.0, 1.0 / max),
        };
        values
            .par_iter_mut()
            .for_each(|v| *v = ((*v - shift).max(0.0) * scale).min(1.0));
        return Ok(VoxelGrid {
            dims,
            spacing: [1.0; 3],
            origin: [0.0; 3],
            values: values.into(),
            scalar_name: "bumps".into(),
        });
    }
    Err(syntax(
        "a volume whose field can reach the asked effective voxel count",
        &format!("{dims:?} with eff={want:?}"),
    ))
}

/// The grid as a voxel data set whose tets split its support cells 5 each (see the module
/// documentation), refused when that split would exceed [`MAX_VOLUME_TETS`].
pub fn volume_voxels(name: &str, grid: VoxelGrid) -> Result<VoxelVolume, ErrorKind> {
    let volume = VoxelVolume::new(name, Arc::new(grid), CellSplit::Five, CellCover::Support)?;
    if volume.num_tets() > MAX_VOLUME_TETS {
        return Err(ErrorKind::Io(format!(
            "the tet split of this volume would have {} tets, above the {} a generated volume may \
             have; use a smaller grid or a smaller eff",
            volume.num_tets(),
            MAX_VOLUME_TETS
        )));
    }
    Ok(volume)
}

/// The grid as a tet mesh of its support cells (see the module documentation).
pub fn volume_mesh(name: &str, grid: VoxelGrid) -> Result<TetMesh, ErrorKind> {
    volume_voxels(name, grid)?.into_mesh()
}

/// The voxel data set a volume spec names (its tets not split yet).
pub fn voxels_from_volume_spec(spec: &str) -> Result<VoxelVolume, LoadError> {
    let s = parse_volume_spec(spec).map_err(|k| LoadError::new(spec, k))?;
    let grid = volume_grid(&s).map_err(|k| LoadError::new(spec, k))?;
    volume_voxels(spec, grid).map_err(|k| LoadError::new(spec, k))
}

/// Builds the mesh a volume spec names.
pub fn from_volume_spec(spec: &str) -> Result<TetMesh, LoadError> {
    voxels_from_volume_spec(spec)?
        .into_mesh()
        .map_err(|k| LoadError::new(spec, k))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse_and_refuse_nonsense() {
        let s = parse_volume_spec("vol:16").unwrap();
        assert_eq!(s.dims, [16; 3]);
        let s = parse_volume_spec("vol:20x12x8:eff=300:seed=4").unwrap();
        assert_eq!((s.dims, s.effective, s.seed), ([20, 12, 8], Some(300), 4));
        for bad in ["vol:1", "vol:8x8", "vol:abc", "vol:8:eff=9999", "vol:8:x=1"] {
            assert!(parse_volume_spec(bad).is_err(), "{bad}");
        }
        assert!(is_volume_spec("vol:8") && !is_volume_spec("standin:bonsai"));
        assert!(!is_volume_spec("box:1k"));
    }

    #[test]
    fn effective_count_is_exact_and_the_mesh_keeps_its_grid() {
        let m = from_volume_spec("vol:24x20x16:eff=1500").unwrap();
        let g = m.source_grid.as_ref().unwrap();
        assert_eq!(g.values.iter().filter(|&v| v > 0.0).count(), 1500);
        assert_eq!(m.num_points(), g.num_voxels());
        assert_eq!(m.points[g.index(3, 2, 1)], [3.0, 2.0, 1.0]);
        // Only support cells are split; all of them are non-degenerate.
        assert!(m.num_tets() < 23 * 19 * 15 * 5 && m.num_tets().is_multiple_of(5));
        assert_eq!(m.repair.degenerate_dropped, 0);
        assert_eq!(m.scalar_range(), (0.0, 1.0));
        let full = from_volume_spec("vol:12").unwrap();
        assert!(full.num_tets() > 0);
    }
}
