//! The papers' data sets at the papers' sizes: those derived from files we have (`spx1`,
//! `spx2`: spx split 1:8 once and twice; `brain`: HeadMRVolume resampled to 98³) and generated
//! stand-ins with the exact tet counts of those we do not have (fuel, f117, kew, torso,
//! fighter, Delta Wing) and the voxel volumes of the splatting paper (dimensions and effective
//! voxel counts of its Table 1).
//!
//! A stand-in matches its original in *size* (tets; for the volumes, grid and effective
//! voxels) and, where the original is non-convex, in having rays leave and re-enter the mesh
//! (an interior cavity); its geometry and field are synthetic, so its images say nothing about
//! the original's. Reports mark rows measured on stand-ins.
//!
//! Also the `NAME@splitN` modifier for any data set ([`crate::split`]).
//!
//! Here the catalogue and its resolution; `domains.rs` the generated domains (shapes cut at an
//! exact tet count), `volumes.rs` the voxel volumes and their tet meshes.

mod domains;
mod volumes;

use std::sync::Arc;

use crate::dataset::{Dataset, LazyDataset, LoadOptions};
use crate::entry::Entry;
use crate::error::{ErrorKind, LoadError};
pub use crate::volume::kuhn_cell_tets;
use crate::volume::{CellSplit, VoxelGrid};
use crate::voxel_volume::{CellCover, VoxelVolume};

pub use domains::{domain_mesh, Shape};
pub use volumes::{
    fuel_volume, resample_trilinear, six_tet_mesh, splat_volume, volume_tet_mesh,
    volume_tet_mesh_within, volume_voxels, volume_voxels_within, MAX_SUPPORT_MESH_TETS,
    MAX_VOLUME_MESH_TETS,
};

/// How a data set of this module is made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Recipe {
    /// A registry data set split 1:8 `levels` times.
    Split { base: &'static str, levels: u32 },
    /// A 64³ synthetic volume (a fuel jet), 6 tets per cube.
    Fuel,
    /// `headmr` resampled (trilinear) to `n`³ points, 6 tets per cube.
    Resampled { base: &'static str, n: usize },
    /// A structured domain with an interior cavity (non-convex) or none (convex), cut at
    /// exactly `tets` tets.
    Domain { shape: Shape, tets: usize },
    /// A splatting volume: grid dims and the exact number of non-empty voxels.
    Volume { dims: [usize; 3], effective: usize },
}
/// One data set of this module.
#[derive(Debug, Clone, Copy)]
pub struct StandIn {
    pub name: &'static str,
    pub recipe: Recipe,
    /// What it stands for, and where the paper's count comes from.
    pub paper: &'static str,
    pub description: &'static str,
    /// Whether it is a generated stand-in (true) or derived from a real file (false).
    pub generated: bool,
}

/// Every data set of this module, by registry name.
pub const STANDINS: &[StandIn] = &[
    StandIn {
        name: "spx1",
        recipe: Recipe::Split { base: "spx", levels: 1 },
        paper: "tiled ray casting's spx1 (103 K tets)",
        description: "spx split 1:8 at edge midpoints (scalar linear): 103,488 tets",
        generated: false,
    },
    StandIn {
        name: "spx2",
        recipe: Recipe::Split { base: "spx", levels: 2 },
        paper: "HAVS's spx2 (827,904 tets), fragment PT's Spx2 (150 K / 828 K)",
        description: "spx split 1:8 twice: 827,904 tets",
        generated: false,
    },
    StandIn {
        name: "fuel",
        recipe: Recipe::Fuel,
        paper: "fragment PT's Fuel (262 K points / 1.5 M tets; the volvis.org volume is not here)",
        description: "stand-in: synthetic 64³ fuel-jet volume, 6 tets per cube: 262,144 points, 1,500,282 tets (convex)",
        generated: true,
    },
    StandIn {
        name: "brain",
        recipe: Recipe::Resampled { base: "headmr", n: 98 },
        paper: "fragment PT's Brain (950 K points / 5.5 M tets; the volvis.org volume is not here)",
        description: "stand-in: HeadMRVolume resampled to 98³ (trilinear), 6 tets per cube: 941,192 points, 5,476,038 tets",
        generated: true,
    },
    StandIn {
        name: "f117",
        recipe: Recipe::Domain { shape: Shape::Faceted, tets: 240_122 },
        paper: "HAVS's and tiled ray casting's f117 (240,122 tets, non-convex)",
        description: "stand-in: box around a faceted aircraft-shaped cavity (non-convex), exactly 240,122 tets",
        generated: true,
    },
    StandIn {
        name: "kew",
        recipe: Recipe::Domain { shape: Shape::Box, tets: 416_926 },
        paper: "HAVS's kew (416,926 tets; shape not described by the paper)",
        description: "stand-in: box (the original's shape is not stated; convex but for the partly filled top layer), exactly 416,926 tets",
        generated: true,
    },
    StandIn {
        name: "torso",
        recipe: Recipe::Domain { shape: Shape::Torso, tets: 1_082_723 },
        paper: "HAVS's torso (1,082,723 tets)",
        description: "stand-in: elliptic body with two lung cavities (non-convex), exactly 1,082,723 tets",
        generated: true,
    },
    StandIn {
        name: "fighter",
        recipe: Recipe::Domain { shape: Shape::Fighter, tets: 1_403_504 },
        paper: "HAVS's fighter (1,403,504 tets, flow around an aircraft)",
        description: "stand-in: box around a fuselage/wing/fin cavity (non-convex), exactly 1,403,504 tets",
        generated: true,
    },
    StandIn {
        name: "deltawing",
        recipe: Recipe::Domain { shape: Shape::Delta, tets: 1_005_675 },
        paper: "GATOR's Delta Wing (211,680 points / 1,005,675 tets, PLOT3D)",
        description: "stand-in: box around a thin delta-plate cavity (non-convex), exactly 1,005,675 tets",
        generated: true,
    },
    StandIn {
        name: "lobster",
        recipe: Recipe::Volume { dims: [324, 301, 56], effective: 233_000 },
        paper: "splatting Table 1 Lobster (324×301×56, 233 K effective voxels)",
        description: "stand-in volume: 324×301×56, exactly 233,000 non-empty voxels",
        generated: true,
    },
    StandIn {
        name: "engine",
        recipe: Recipe::Volume { dims: [256, 256, 128], effective: 1_300_000 },
        paper: "splatting Table 1 Engine (256²×128, 1.3 M effective voxels)",
        description: "stand-in volume: 256×256×128, exactly 1,300,000 non-empty voxels",
        generated: true,
    },
    StandIn {
        name: "teapot",
        recipe: Recipe::Volume { dims: [256, 256, 178], effective: 4_900_000 },
        paper: "splatting Table 1 BostonTeapot (256²×178, 4.9 M effective voxels)",
        description: "stand-in volume: 256×256×178, exactly 4,900,000 non-empty voxels; tets split only the cubes with a non-empty corner",
        generated: true,
    },
    StandIn {
        name: "aneurism",
        recipe: Recipe::Volume { dims: [256, 256, 256], effective: 169_000 },
        paper: "splatting Table 1 Aneurism (256³, 169 K effective voxels)",
        description: "stand-in volume: 256³, exactly 169,000 non-empty voxels; tets split only the cubes with a non-empty corner",
        generated: true,
    },
    StandIn {
        name: "bonsai",
        recipe: Recipe::Volume { dims: [256, 256, 256], effective: 1_300_000 },
        paper: "splatting Table 1 Bonsai (256³, 1.3 M effective voxels)",
        description: "stand-in volume: 256³, exactly 1,300,000 non-empty voxels; tets split only the cubes with a non-empty corner",
        generated: true,
    },
    StandIn {
        name: "stagbeetle",
        recipe: Recipe::Volume { dims: [832, 832, 494], effective: 13_800_000 },
        paper: "splatting Table 1 StagBeetle (832²×494, 13.8 M effective voxels)",
        description: "stand-in volume: 832×832×494, exactly 13,800,000 non-empty voxels; tets split only the cubes with a non-empty corner",
        generated: true,
    },
];
/// Other spellings of stand-ins: the papers' own names where ours are shorter.
const ALIASES: [(&str, &str); 1] = [("bostonteapot", "teapot")];

/// The stand-in called `name` (case-insensitive, optionally written `standin:NAME`, or by an
/// alias such as the paper's `BostonTeapot`), if any.
pub fn find(name: &str) -> Option<&'static StandIn> {
    let bare = match name.get(..8) {
        Some(head) if head.eq_ignore_ascii_case("standin:") => &name[8..],
        _ => name,
    };
    let canonical = ALIASES
        .iter()
        .find(|(alias, _)| alias.eq_ignore_ascii_case(bare))
        .map_or(bare, |(_, n)| n);
    STANDINS
        .iter()
        .find(|s| s.name.eq_ignore_ascii_case(canonical))
}

/// Whether `name` is a generated stand-in (rows on it are marked in reports).
pub fn is_generated(name: &str) -> bool {
    find(name).is_some_and(|s| s.generated)
}

/// Registry entries of this module; `named` are the registry's file entries (for presence).
pub fn entries(named: &[Entry]) -> Vec<Entry> {
    STANDINS
        .iter()
        .map(|s| {
            let base = match s.recipe {
                Recipe::Split { base, .. } | Recipe::Resampled { base, .. } => Some(base),
                _ => None,
            };
            let base_entry = base.and_then(|b| named.iter().find(|e| e.name == b));
            Entry {
                name: s.name.to_string(),
                description: s.description.to_string(),
                files: base_entry.map(|e| e.files.clone()).unwrap_or_default(),
                present: base_entry.is_none_or(|e| e.present),
                paper: s.paper,
            }
        })
        .collect()
}

/// How a stand-in loads the data set it is derived from (the registry's `resolve`, passed in
/// so that this module does not depend on the registry that depends on it).
pub type ResolveBase<'a> = &'a dyn Fn(&str, &LoadOptions) -> Result<Dataset, LoadError>;

/// Resolves a name of this module or a `BASE@splitN` modifier; `None` when `key` is neither.
pub fn resolve(
    resolve_base: ResolveBase,
    key: &str,
    options: &LoadOptions,
) -> Option<Result<Dataset, LoadError>> {
    let lazy = resolve_lazy(resolve_base, key, options)?;
    Some(lazy.and_then(|ds| {
        let mut ds = ds.into_dataset()?;
        ds.attach_grid();
        Ok(ds)
    }))
}

/// [`resolve`], leaving the volumes (`fuel`, `brain`, the splatting stand-ins) as voxels whose
/// tets are split on first use.
pub fn resolve_lazy(
    resolve_base: ResolveBase,
    key: &str,
    options: &LoadOptions,
) -> Option<Result<LazyDataset, LoadError>> {
    if let Some((base, modifier)) = key.rsplit_once('@') {
        let levels = crate::split::parse_modifier(modifier)?;
        return Some(split_dataset(resolve_base, key, base, levels, options).map(Into::into));
    }
    let s = find(key)?;
    Some(build(resolve_base, s, options).map(|mut ds| {
        ds.source = format!("{} ({})", s.name, s.description);
        ds
    }))
}

/// A missing file of a base data set, re-worded to name the derived one too.
fn derived_error(key: &str, e: LoadError) -> LoadError {
    match e.kind {
        ErrorKind::MissingDataFile {
            dataset,
            file,
            origin,
        } => LoadError {
            kind: ErrorKind::MissingDataFile {
                dataset: format!("{key} (derived from {dataset})"),
                file,
                origin,
            },
            ..e
        },
        _ => e,
    }
}

fn split_dataset(
    resolve_base: ResolveBase,
    key: &str,
    base: &str,
    levels: u32,
    options: &LoadOptions,
) -> Result<Dataset, LoadError> {
    let ds = resolve_base(base, options).map_err(|e| derived_error(key, e))?;
    let mut mesh = crate::split::split(&ds.mesh, levels).map_err(|k| LoadError::new(key, k))?;
    mesh.name = key.to_string();
    Ok(Dataset {
        mesh,
        volume: None,
        source: format!("{} split 1:8 ×{levels}", ds.source),
    })
}

fn build(
    resolve_base: ResolveBase,
    s: &StandIn,
    options: &LoadOptions,
) -> Result<LazyDataset, LoadError> {
    let err = |k: ErrorKind| LoadError::new(s.name, k);
    if let Some(want) = &options.scalar {
        if matches!(
            s.recipe,
            Recipe::Fuel | Recipe::Domain { .. } | Recipe::Volume { .. }
        ) {
            return Err(err(ErrorKind::MissingArray {
                name: want.clone(),
                available: vec!["(generated field)".into()],
            }));
        }
    }
    let every_cube = |grid: VoxelGrid| {
        VoxelVolume::new(s.name, Arc::new(grid), CellSplit::Six, CellCover::All)
            .map(|v| LazyDataset::from_voxels(v, s.name))
            .map_err(err)
    };
    match s.recipe {
        Recipe::Split { base, levels } => {
            let mut ds = split_dataset(resolve_base, s.name, base, levels, options)?;
            ds.mesh.name = s.name.to_string();
            Ok(ds.into())
        }
        Recipe::Fuel => every_cube(fuel_volume()),
        Recipe::Resampled { base, n } => {
            let ds = resolve_base(base, options).map_err(|e| derived_error(s.name, e))?;
            let Some(vol) = ds.volume else {
                return Err(err(ErrorKind::Invalid(format!(
                    "{base} is not a voxel volume, cannot resample it"
                ))));
            };
            every_cube(resample_trilinear(&vol, [n; 3]))
        }
        Recipe::Domain { shape, tets } => {
            let mut mesh = domain_mesh(shape, tets, seed_of(s.name)).map_err(err)?;
            mesh.name = s.name.to_string();
            Ok(Dataset {
                mesh,
                volume: None,
                source: String::new(),
            }
            .into())
        }
        Recipe::Volume { dims, effective } => {
            let grid = splat_volume(dims, effective, seed_of(s.name));
            let volume = volume_voxels(s.name, Arc::new(grid)).map_err(err)?;
            Ok(LazyDataset::from_voxels(volume, s.name))
        }
    }
}

/// A fixed seed per name, so every stand-in is the same mesh on every machine.
fn seed_of(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    })
}

#[cfg(test)]
mod tests;
