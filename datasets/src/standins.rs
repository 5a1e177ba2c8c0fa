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

use rayon::prelude::*;

use std::sync::Arc;

use crate::dataset::{Dataset, LazyDataset, LoadOptions};
use crate::entry::Entry;
use crate::error::{ErrorKind, LoadError};
use crate::generate::{Field, FieldEval};
use crate::grid::GridValues;
pub use crate::volume::kuhn_cell_tets;
use crate::volume::{hex_cell_tets, split_cells, CellSplit, VoxelGrid};
use crate::voxel_volume::{CellCover, VoxelVolume};
use crate::TetMesh;

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

/// A volume's 6-tet split covers every cube up to this many tets; beyond, only the cubes of
/// the support (see [`volume_tet_mesh`]).
pub const MAX_VOLUME_MESH_TETS: usize = 60_000_000;

/// The most tets a support split may have: 16 B each, so 2.4 GB of tets, and about twice that
/// while [`TetMesh::new`] checks their orientation. The largest stand-in (StagBeetle, 13.8 M
/// effective voxels) stays below it.
pub const MAX_SUPPORT_MESH_TETS: usize = 150_000_000;

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

/// A voxel grid as a tet mesh, 6 tets per cube ([`kuhn_cell_tets`]), every cube.
pub fn six_tet_mesh(grid: &VoxelGrid) -> Result<TetMesh, ErrorKind> {
    kuhn_mesh(grid, |_, _, _| true)
}

/// A generated volume's tet mesh: every cube ([`six_tet_mesh`]) while that stays within
/// [`MAX_VOLUME_MESH_TETS`]; beyond it only the support, the cubes with a non-zero corner. The
/// cubes left out hold 0 at all eight corners, so under a transfer function with κ(0) = 0 (the
/// one that defines a stand-in's effective voxels) both meshes give the same image with the
/// same camera and optics (a run fits those to the mesh's bounds, so it frames the support;
/// `tests/roundtrip_generated.rs` checks the images agree). Under one
/// with κ(0) > 0 the data set *is* the support: the splatter splats only grid points that a tet
/// uses, so every algorithm still draws the same data. Points stay the whole grid, in grid
/// order, which is what lets [`TetMesh::source_grid`] stand for them.
pub fn volume_tet_mesh(grid: &VoxelGrid) -> Result<TetMesh, ErrorKind> {
    volume_tet_mesh_within(grid, MAX_VOLUME_MESH_TETS)
}

/// [`volume_tet_mesh`] with the full split's limit as a parameter (0: always the support).
pub fn volume_tet_mesh_within(grid: &VoxelGrid, full_limit: usize) -> Result<TetMesh, ErrorKind> {
    volume_voxels_within("volume", Arc::new(grid.clone()), full_limit)?.into_mesh()
}

/// The voxel data set of a generated volume, its tets ([`volume_tet_mesh`]) not split yet.
pub fn volume_voxels(name: &str, grid: Arc<VoxelGrid>) -> Result<VoxelVolume, ErrorKind> {
    volume_voxels_within(name, grid, MAX_VOLUME_MESH_TETS)
}

/// [`volume_voxels`] with the full split's limit as a parameter (0: always the support).
pub fn volume_voxels_within(
    name: &str,
    grid: Arc<VoxelGrid>,
    full_limit: usize,
) -> Result<VoxelVolume, ErrorKind> {
    let d = grid.dims;
    let cubes: usize = d.iter().map(|x| x.saturating_sub(1)).product();
    if cubes * 6 <= full_limit {
        return VoxelVolume::new(name, grid, CellSplit::Six, CellCover::All);
    }
    let volume = VoxelVolume::new(name, grid, CellSplit::Six, CellCover::Support)?;
    if volume.num_tets() > MAX_SUPPORT_MESH_TETS {
        return Err(ErrorKind::Invalid(format!(
            "the {}×{}×{} volume's support split would have {} tets (more than \
             {MAX_SUPPORT_MESH_TETS})",
            d[0],
            d[1],
            d[2],
            volume.num_tets()
        )));
    }
    Ok(volume)
}

/// The 6-tet split of the cubes `keep` accepts, with every grid point a mesh point.
fn kuhn_mesh(
    grid: &VoxelGrid,
    keep: impl Fn(usize, usize, usize) -> bool + Sync,
) -> Result<TetMesh, ErrorKind> {
    split_cells(grid, CellSplit::Six, keep)
}

/// The fuel stand-in: a 64³ grid on [-1,1]³ holding a synthetic jet — fuel entering at the
/// bottom along the z axis, spreading and thinning as it rises, with a ripple along the jet.
pub fn fuel_volume() -> VoxelGrid {
    let n = 64;
    let h = 2.0 / (n - 1) as f64;
    let values: Vec<f32> = (0..n * n * n)
        .into_par_iter()
        .map(|g| {
            let (x, y, z) = (
                -1.0 + (g % n) as f64 * h,
                -1.0 + ((g / n) % n) as f64 * h,
                -1.0 + (g / (n * n)) as f64 * h,
            );
            let t = (z + 1.0) * 0.5;
            let sigma = 0.06 + 0.3 * t;
            let r2 = x * x + y * y;
            let core = (-(r2) / (2.0 * sigma * sigma)).exp() * (1.0 - 0.6 * t);
            let ripple = 1.0 + 0.15 * (10.0 * t + 4.0 * x).sin();
            (core * ripple).max(0.0) as f32
        })
        .collect();
    VoxelGrid {
        dims: [n; 3],
        spacing: [h; 3],
        origin: [-1.0; 3],
        values: values.into(),
        scalar_name: "fuel_density".into(),
    }
}

/// Trilinear resampling of `grid` onto `dims` points spanning the same box.
pub fn resample_trilinear(grid: &VoxelGrid, dims: [usize; 3]) -> VoxelGrid {
    let ext: [f64; 3] = std::array::from_fn(|a| (grid.dims[a] - 1) as f64 * grid.spacing[a]);
    let spacing: [f64; 3] = std::array::from_fn(|a| {
        if dims[a] > 1 {
            ext[a] / (dims[a] - 1) as f64
        } else {
            grid.spacing[a]
        }
    });
    let sample = |q: [f64; 3]| -> f32 {
        let mut i0 = [0usize; 3];
        let mut f = [0.0f64; 3];
        for a in 0..3 {
            let u =
                ((q[a] - grid.origin[a]) / grid.spacing[a]).clamp(0.0, (grid.dims[a] - 1) as f64);
            let base = (u.floor() as usize).min(grid.dims[a].saturating_sub(2));
            i0[a] = base;
            f[a] = u - base as f64;
        }
        let mut acc = 0.0f64;
        for c in 0..8 {
            let d = [c & 1, (c >> 1) & 1, (c >> 2) & 1];
            let w: f64 = (0..3)
                .map(|a| if d[a] == 1 { f[a] } else { 1.0 - f[a] })
                .product();
            let ii: [usize; 3] = std::array::from_fn(|a| (i0[a] + d[a]).min(grid.dims[a] - 1));
            acc += w * grid.values.get(grid.index(ii[0], ii[1], ii[2])) as f64;
        }
        acc as f32
    };
    let n = dims.iter().product::<usize>();
    let values: Vec<f32> = (0..n)
        .into_par_iter()
        .map(|g| {
            let ijk = [
                g % dims[0],
                (g / dims[0]) % dims[1],
                g / (dims[0] * dims[1]),
            ];
            sample(std::array::from_fn(|a| {
                grid.origin[a] + ijk[a] as f64 * spacing[a]
            }))
        })
        .collect();
    VoxelGrid {
        dims,
        spacing,
        origin: grid.origin,
        values: values.into(),
        scalar_name: grid.scalar_name.clone(),
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
                let ijk = [g % d[0], (g / d[0]) % d[1], g / (d[0] * d[1])];
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

/// A splatting stand-in volume: `dims` grid points of a seeded blob field of which exactly
/// `effective` voxels are non-zero (the largest values; ties broken by voxel index), the rest
/// 0 — the paper's "effective voxels" under any transfer function that maps 0 to transparent.
/// The values are 16-bit levels ([`GridValues::Levels`]), as the papers' scanner volumes
/// are: StagBeetle's 342 M voxels take 684 MB, and no f32 copy is made on the way.
pub fn splat_volume(dims: [usize; 3], effective: usize, seed: u64) -> VoxelGrid {
    let n: usize = dims.iter().product();
    let field = FieldEval::new(Field::Blobs, seed);
    let h: [f64; 3] = std::array::from_fn(|a| 2.0 / (dims[a].max(2) - 1) as f64);
    // Levels of a step the field cannot exceed, at least 1: 0 is kept for "empty".
    let step = field.upper_bound().unwrap_or(1.0).max(f64::MIN_POSITIVE) / u16::MAX as f64;
    // Sampled separably: eight exp per point were most of StagBeetle's generation.
    let lattice = field
        .on_lattice(dims, [-1.0; 3], h)
        .expect("the blob field is separable");
    let mut levels: Vec<u16> = (0..n)
        .into_par_iter()
        .map(|g| {
            let ijk = [
                g % dims[0],
                (g / dims[0]) % dims[1],
                g / (dims[0] * dims[1]),
            ];
            (lattice.at(ijk) / step).round().clamp(1.0, u16::MAX as f64) as u16
        })
        .collect();
    let effective = effective.min(n);
    // The smallest level τ with at most `effective` voxels above it, from the levels'
    // histogram; of the voxels at τ, the first in index order fill the count.
    let histogram = levels
        .par_iter()
        .fold(
            || vec![0usize; 1 << 16],
            |mut h, &l| {
                h[l as usize] += 1;
                h
            },
        )
        .reduce(
            || vec![0usize; 1 << 16],
            |mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                a
            },
        );
    let (mut tau, mut above) = (u16::MAX as usize, 0usize);
    while tau > 0 && above + histogram[tau] <= effective {
        above += histogram[tau];
        tau -= 1;
    }
    let mut ties_left = effective - above;
    for l in levels.iter_mut() {
        if *l as usize > tau {
            continue;
        }
        if *l as usize == tau && ties_left > 0 {
            ties_left -= 1;
        } else {
            *l = 0;
        }
    }
    VoxelGrid {
        dims,
        spacing: h,
        origin: [-1.0; 3],
        values: GridValues::Levels {
            levels,
            step: step as f32,
        },
        scalar_name: field.name().into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kuhn_split_is_conforming_and_positive() {
        let grid = VoxelGrid {
            dims: [4, 3, 5],
            spacing: [1.0, 0.5, 2.0],
            origin: [0.0; 3],
            values: vec![0.0; 60].into(),
            scalar_name: "z".into(),
        };
        let m = six_tet_mesh(&grid).unwrap();
        assert_eq!(m.num_tets(), 3 * 2 * 4 * 6);
        assert_eq!(m.repair.inverted_fixed, 0);
        assert_eq!(m.repair.degenerate_dropped, 0);
        let quads = 2 * (3 * 2 + 2 * 4 + 3 * 4);
        assert_eq!(m.boundary_faces().len(), 2 * quads);
        assert!(m.is_convex());
    }

    #[test]
    fn domains_hit_exact_counts_and_cavities_make_them_non_convex() {
        for (shape, target) in [
            (Shape::Faceted, 20_011),
            (Shape::Box, 9_999),
            (Shape::Torso, 15_000),
        ] {
            let m = domain_mesh(shape, target, 3).unwrap();
            assert_eq!(m.num_tets(), target, "{shape:?}");
            assert_eq!(m.repair.degenerate_dropped, 0);
            assert_eq!(m.repair.unused_points, 0);
            if !shape.is_convex() {
                assert!(!m.is_convex(), "{shape:?}");
            }
        }
    }

    #[test]
    fn large_volumes_split_only_their_support() {
        let g = splat_volume([12, 10, 9], 40, 3);
        let full = volume_tet_mesh_within(&g, usize::MAX).unwrap();
        assert_eq!(full.num_tets(), 11 * 9 * 8 * 6);
        let sparse = volume_tet_mesh_within(&g, 0).unwrap();
        let support = (0..8)
            .flat_map(|k| (0..9).flat_map(move |j| (0..11).map(move |i| (i, j, k))))
            // Counted here independently of `VoxelGrid::cube_has_nonzero_corner`.
            .filter(|&(i, j, k)| {
                (0..8).any(|b| {
                    g.values
                        .get(g.index(i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1)))
                        != 0.0
                })
            })
            .count();
        assert!(support > 0 && support < 11 * 9 * 8);
        assert_eq!(sparse.num_tets(), support * 6);
        // Every grid point stays a mesh point, in grid order, so the grid can stand for them.
        assert_eq!(sparse.num_points(), g.num_voxels());
        assert_eq!(
            sparse.points[g.index(3, 2, 1)],
            g.point(3, 2, 1).map(|c| c as f32)
        );
        assert_eq!(sparse.repair.degenerate_dropped, 0);
        // Each non-zero voxel is a vertex of some tet of the support.
        let mut used = vec![false; g.num_voxels()];
        sparse
            .tets
            .iter()
            .flatten()
            .for_each(|&v| used[v as usize] = true);
        assert!(g.values.iter().zip(&used).all(|(v, &u)| v == 0.0 || u));
    }

    #[test]
    fn standins_answer_to_the_papers_spellings() {
        for name in [
            "teapot",
            "standin:teapot",
            "BostonTeapot",
            "standin:BostonTeapot",
        ] {
            assert_eq!(find(name).map(|s| s.name), Some("teapot"), "{name}");
        }
        assert_eq!(find("standin:lobster").map(|s| s.name), Some("lobster"));
        assert!(find("standin:").is_none() && find("standin:nothing").is_none());
    }

    #[test]
    fn splat_volumes_have_exactly_the_effective_voxels() {
        let g = splat_volume([20, 17, 9], 777, 5);
        assert_eq!(g.values.iter().filter(|&v| v != 0.0).count(), 777);
        assert!(matches!(g.values, GridValues::Levels { .. }));
        let r = resample_trilinear(&g, [7, 7, 7]);
        assert_eq!(r.values.len(), 343);
        assert_eq!(r.values.get(0), g.values.get(0));
    }
}
