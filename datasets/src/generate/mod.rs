//! Deterministic mesh generators for scaling curves and for the cases the papers' data sets
//! cannot cover at every size.
//!
//! A spec is `KIND:SIZE[:key=value…]`, e.g. `box:200k`, `shell:1m`, `slivers:50k`,
//! `box:200k:field=blobs`, `tunnels:1m:seed=7`. SIZE is the target tet count (`k`/`m`
//! suffixes, decimals allowed: `1.5m`); the result is within a few percent of it (exact counts
//! are documented per generator). Keys: `field=ml|blobs|radial|linear`, `seed=N`.
//!
//! | kind | mesh | default field |
//! |---|---|---|
//! | `box` | cube [-1,1]³, structured grid, 5 tets per cell (convex) | Marschner–Lobb |
//! | `shell` | hollow sphere r ∈ [0.5, 1] (cubed-sphere grid, 6 tets per cell): rays through the middle cross the boundary 4 times | blobs |
//! | `tunnels` | cube pierced by 3×2×2 square tunnels along the axes: rays leave and re-enter up to 6 times | Marschner–Lobb |
//! | `slivers` | cube whose z layers are thin at random (0.5–4 % of a cell) and whose points are jittered: many flat tets (aspect ratio > 10), still valid and conforming | blobs |
//! | `onion` | the shell's radii with one cell per cube face and N/36 radial layers: a cube-shaped onion of nested sliver layers (aspect ratio ≫ 10), a stress case for HAVS's k-buffer | blobs |
//!
//! Quality: every kind except `slivers` and `onion` keeps each tet's aspect ratio (longest edge
//! over 2·√6·inradius, [`crate::QualityStats`]) at most [`MAX_ASPECT`] at every size from 1 k to
//! 20 M tets, so none is a sliver; the generator tests sweep the sizes.
//!
//! Everything is a pure function of (spec, seed): random numbers come from a counter-based
//! SplitMix64 hash of (seed, stream, index), so parallel generation is deterministic and does
//! not depend on a crate's generator staying stable across versions.
//!
//! Here the spec, its parsing and the dispatch; `field.rs` the random numbers and the point
//! fields, `boxes.rs` the structured boxes (`box`, `slivers`, `tunnels`), `shell.rs` the
//! cubed-sphere shells (`shell`, `onion`).

mod boxes;
mod field;
mod shell;

use rayon::prelude::*;

use crate::error::{ErrorKind, LoadError};
use crate::TetMesh;

use boxes::{box_mesh, slivers_mesh, tunnels_mesh};
use shell::shell_mesh;

pub use boxes::{box_cells, TUNNEL_LINES};
pub use field::{FieldEval, Lattice};
pub use shell::{onion_cells, shell_cells, SHELL_RADII};

/// Largest accepted target (u32 indices and memory stay comfortable).
pub const MAX_TETS: usize = 100_000_000;

/// Generator kinds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Box,
    Shell,
    Tunnels,
    Slivers,
    Onion,
}

/// Largest tet aspect ratio of the quality generators (`box`, `shell`, `tunnels`) at any size.
/// Measured maxima from 1 k to 1 M tets (tests/generator_quality.rs): box 1.86 (the 5-tet split
/// of cells whose axes differ by up to 2×), tunnels 1.86 (the same cells), shell 4.15 (at 1 k,
/// the coarsest cubed-sphere cells, which the equiangular map skews most at the cube's corners).
/// The rules that bound them (box axes within 2×, shell cells 1–2.5× as thick as wide) do not
/// depend on the size.
pub const MAX_ASPECT: f64 = 5.0;

impl Kind {
    pub const ALL: [Kind; 5] = [
        Kind::Box,
        Kind::Shell,
        Kind::Tunnels,
        Kind::Slivers,
        Kind::Onion,
    ];
    pub fn name(self) -> &'static str {
        match self {
            Kind::Box => "box",
            Kind::Shell => "shell",
            Kind::Tunnels => "tunnels",
            Kind::Slivers => "slivers",
            Kind::Onion => "onion",
        }
    }
    pub fn description(self) -> &'static str {
        match self {
            Kind::Box => "tetrahedralised cube [-1,1]^3 (structured, 5 tets/cell), convex",
            Kind::Shell => "hollow sphere r in [0.5,1] (cubed-sphere grid, 6 tets/cell), non-convex: rays cross 4 times",
            Kind::Tunnels => "cube with 12 square tunnels along the axes, non-convex: rays leave and re-enter",
            Kind::Slivers => "cube with randomly thin layers and jittered points: many flat tets (aspect > 10)",
            Kind::Onion => "hollow sphere r in [0.5,1] with one cell per cube face and N/36 radial layers: nested sliver shells (HAVS k-buffer stress case)",
        }
    }
    fn default_field(self) -> Field {
        match self {
            Kind::Box | Kind::Tunnels => Field::MarschnerLobb,
            Kind::Shell | Kind::Slivers | Kind::Onion => Field::Blobs,
        }
    }
}

/// Analytic point fields, evaluated on [-1,1]³.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    /// Marschner & Lobb 1994 test signal, f_M = 6, α = 0.25 (values in [0, 1]).
    MarschnerLobb,
    /// A sum of 8 seeded Gaussian blobs.
    Blobs,
    /// Distance from the origin.
    Radial,
    /// 0.3 + 0.5x − 0.25y + 0.125z (resampling and interpolation tests).
    Linear,
}

impl Field {
    pub fn parse(s: &str) -> Option<Field> {
        Some(match s {
            "ml" | "marschner-lobb" | "marschnerlobb" => Field::MarschnerLobb,
            "blobs" | "gauss" | "gaussian" => Field::Blobs,
            "radial" => Field::Radial,
            "linear" => Field::Linear,
            _ => return None,
        })
    }
    pub fn name(self) -> &'static str {
        match self {
            Field::MarschnerLobb => "marschner_lobb",
            Field::Blobs => "blobs",
            Field::Radial => "radial",
            Field::Linear => "linear",
        }
    }
}

/// A parsed generator spec.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Spec {
    pub kind: Kind,
    pub target_tets: usize,
    pub field: Field,
    /// Seed given in the spec (`seed=N`), overriding the caller's.
    pub seed: Option<u64>,
}

/// Whether `s` looks like a generator spec (`KIND:…` with a known kind).
pub fn is_spec(s: &str) -> bool {
    let head = s.split(':').next().unwrap_or("").to_ascii_lowercase();
    s.contains(':') && Kind::ALL.iter().any(|k| k.name() == head)
}

/// Parses `123`, `200k`, `1m`, `1.5M` into a count.
pub fn parse_size(s: &str) -> Option<usize> {
    let s = s.trim().to_ascii_lowercase();
    let (num, mul) = match s.chars().last()? {
        'k' => (&s[..s.len() - 1], 1e3),
        'm' => (&s[..s.len() - 1], 1e6),
        _ => (&s[..], 1.0),
    };
    let v: f64 = num.parse().ok()?;
    let n = (v * mul).round();
    (v.is_finite() && n >= 1.0 && n <= MAX_TETS as f64).then_some(n as usize)
}

/// Parses a spec string (see the module documentation).
pub fn parse_spec(spec: &str) -> Result<Spec, ErrorKind> {
    let mut parts = spec.split(':');
    let head = parts.next().unwrap_or("").trim().to_ascii_lowercase();
    let kind = Kind::ALL
        .into_iter()
        .find(|k| k.name() == head)
        .ok_or_else(|| ErrorKind::Syntax {
            expected: "a generator kind (box, shell, tunnels, slivers, onion)".into(),
            found: head.clone(),
        })?;
    let size = parts.next().unwrap_or("");
    let target_tets = parse_size(size).ok_or_else(|| ErrorKind::Syntax {
        expected: format!("a tet count between 1 and {MAX_TETS} such as 200k or 1m"),
        found: size.into(),
    })?;
    let mut out = Spec {
        kind,
        target_tets,
        field: kind.default_field(),
        seed: None,
    };
    for opt in parts {
        let (k, v) = opt.split_once('=').unwrap_or((opt, ""));
        match k.trim() {
            "field" => {
                out.field = Field::parse(v.trim()).ok_or_else(|| ErrorKind::Syntax {
                    expected: "field=ml|blobs|radial|linear".into(),
                    found: v.into(),
                })?
            }
            "seed" => {
                out.seed = Some(v.trim().parse().map_err(|_| ErrorKind::Syntax {
                    expected: "seed=<integer>".into(),
                    found: v.into(),
                })?)
            }
            _ => {
                return Err(ErrorKind::Syntax {
                    expected: "an option field=… or seed=…".into(),
                    found: opt.into(),
                })
            }
        }
    }
    Ok(out)
}

/// Generates the mesh a spec names; `seed` is used unless the spec gives `seed=N`.
/// Errors carry the spec in place of a file name.
pub fn from_spec(spec: &str, seed: u64) -> Result<TetMesh, LoadError> {
    let s = parse_spec(spec).map_err(|k| LoadError::new(spec, k))?;
    let mut mesh = generate(&s, s.seed.unwrap_or(seed)).map_err(|k| LoadError::new(spec, k))?;
    mesh.name = spec.to_string();
    Ok(mesh)
}

/// Generates a parsed spec.
pub fn generate(spec: &Spec, seed: u64) -> Result<TetMesh, ErrorKind> {
    let f = FieldEval::new(spec.field, seed);
    match spec.kind {
        Kind::Box => box_mesh(spec.target_tets, &f),
        Kind::Shell => shell_mesh(shell_cells(spec.target_tets), "shell", &f),
        Kind::Onion => shell_mesh(onion_cells(spec.target_tets), "onion", &f),
        Kind::Tunnels => tunnels_mesh(spec.target_tets, &f),
        Kind::Slivers => slivers_mesh(spec.target_tets, &f, seed),
    }
}

fn finish(
    name: &str,
    points: Vec<[f64; 3]>,
    f: &FieldEval,
    tets: Vec<[u32; 4]>,
) -> Result<TetMesh, ErrorKind> {
    if points.len() > u32::MAX as usize {
        return Err(ErrorKind::IndexOverflow {
            what: "points".into(),
            count: points.len() as u64,
        });
    }
    let scalars: Vec<f32> = points.par_iter().map(|&p| f.eval(p) as f32).collect();
    let points: Vec<[f32; 3]> = points.par_iter().map(|p| p.map(|c| c as f32)).collect();
    TetMesh::new(name, points, scalars, f.name(), tets)
}

#[cfg(test)]
mod tests;
