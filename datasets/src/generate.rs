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

use std::f64::consts::PI;

use rayon::prelude::*;

use crate::error::{ErrorKind, LoadError};
use crate::volume::structured_tets;
use crate::TetMesh;

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

// ---------------------------------------------------------------------------------------------
// Random numbers and fields

/// SplitMix64 finaliser (Steele et al. 2014): a high-quality 64-bit mix.
fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Uniform in [0, 1) from (seed, stream, index), independent of evaluation order.
fn rand01(seed: u64, stream: u64, index: u64) -> f64 {
    let h = mix64(mix64(seed ^ mix64(stream.wrapping_mul(0xD1B5_4A32_D192_ED03))) ^ index);
    (h >> 11) as f64 / (1u64 << 53) as f64
}

struct Blob {
    center: [f64; 3],
    inv_two_sigma2: f64,
    amplitude: f64,
}

/// A field ready to evaluate (blobs drawn from the seed once).
pub struct FieldEval {
    field: Field,
    blobs: Vec<Blob>,
}

impl FieldEval {
    /// A value the field never exceeds, where one is known: the blobs' summed amplitudes.
    pub fn upper_bound(&self) -> Option<f64> {
        match self.field {
            Field::Blobs => Some(self.blobs.iter().map(|b| b.amplitude.max(0.0)).sum()),
            _ => None,
        }
    }

    pub fn new(field: Field, seed: u64) -> FieldEval {
        let blobs = (0..8u64)
            .map(|b| {
                let r = |c: u64| rand01(seed, 1000 + b, c);
                let sigma = 0.15 + 0.3 * r(3);
                Blob {
                    center: [r(0), r(1), r(2)].map(|u| -0.7 + 1.4 * u),
                    inv_two_sigma2: 1.0 / (2.0 * sigma * sigma),
                    amplitude: 0.4 + 0.6 * r(4),
                }
            })
            .collect();
        FieldEval { field, blobs }
    }

    pub fn name(&self) -> &'static str {
        self.field.name()
    }

    /// The blob field sampled on the lattice `origin + i·h` (`dims` points per axis), where a
    /// sample costs a few multiplications: each blob's Gaussian is the product of one factor
    /// per axis, computed once per grid line. Equal to [`FieldEval::eval`] at the lattice points
    /// up to rounding (the product of three `exp` against one `exp` of the sum). `None` for
    /// the other fields.
    pub fn on_lattice(&self, dims: [usize; 3], origin: [f64; 3], h: [f64; 3]) -> Option<Lattice> {
        if self.field != Field::Blobs {
            return None;
        }
        let factors = std::array::from_fn(|a| {
            self.blobs
                .iter()
                .flat_map(|b| {
                    (0..dims[a]).map(move |i| {
                        let d = origin[a] + i as f64 * h[a] - b.center[a];
                        (-d * d * b.inv_two_sigma2).exp()
                    })
                })
                .collect()
        });
        Some(Lattice {
            dims,
            amplitudes: self.blobs.iter().map(|b| b.amplitude).collect(),
            factors,
        })
    }

    pub fn eval(&self, p: [f64; 3]) -> f64 {
        let [x, y, z] = p;
        match self.field {
            Field::MarschnerLobb => {
                // Marschner & Lobb 1994, eq. for ρ(x,y,z) on [-1,1]³ with f_M = 6, α = 0.25.
                const FM: f64 = 6.0;
                const ALPHA: f64 = 0.25;
                let r = (x * x + y * y).sqrt();
                let rho_r = (2.0 * PI * FM * (PI * r / 2.0).cos()).cos();
                (1.0 - (PI * z / 2.0).sin() + ALPHA * (1.0 + rho_r)) / (2.0 * (1.0 + ALPHA))
            }
            Field::Blobs => self
                .blobs
                .iter()
                .map(|b| {
                    let d2 = (0..3).map(|a| (p[a] - b.center[a]).powi(2)).sum::<f64>();
                    b.amplitude * (-d2 * b.inv_two_sigma2).exp()
                })
                .sum(),
            Field::Radial => (x * x + y * y + z * z).sqrt(),
            Field::Linear => 0.3 + 0.5 * x - 0.25 * y + 0.125 * z,
        }
    }
}

/// The blob field on a lattice ([`FieldEval::on_lattice`]).
pub struct Lattice {
    dims: [usize; 3],
    amplitudes: Vec<f64>,
    /// Per axis, blob-major: `factors[a][b * dims[a] + i]`.
    factors: [Vec<f64>; 3],
}

impl Lattice {
    /// The field at lattice point (i, j, k).
    pub fn at(&self, [i, j, k]: [usize; 3]) -> f64 {
        let [nx, ny, nz] = self.dims;
        let [fx, fy, fz] = &self.factors;
        self.amplitudes
            .iter()
            .enumerate()
            .map(|(b, amp)| amp * fx[b * nx + i] * fy[b * ny + j] * fz[b * nz + k])
            .sum()
    }
}

// ---------------------------------------------------------------------------------------------
// Structured boxes

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
            let ijk = [g % d[0], (g / d[0]) % d[1], g / (d[0] * d[1])];
            let mut p = [0, 1, 2].map(|a| -1.0 + 2.0 * ijk[a] as f64 / cells[a] as f64);
            if let Some(z) = z_levels {
                p[2] = z[ijk[2]];
            }
            p
        })
        .collect()
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

/// `box`: 5·a·b·c tets with (a, b, c) = [`box_cells`]`(target)`.
fn box_mesh(target: usize, f: &FieldEval) -> Result<TetMesh, ErrorKind> {
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
fn slivers_mesh(target: usize, f: &FieldEval, seed: u64) -> Result<TetMesh, ErrorKind> {
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
fn tunnels_mesh(target: usize, f: &FieldEval) -> Result<TetMesh, ErrorKind> {
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

// ---------------------------------------------------------------------------------------------
// Spherical shell

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
fn shell_mesh(cells: (usize, usize), name: &str, f: &FieldEval) -> Result<TetMesh, ErrorKind> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blob_lattice_agrees_with_the_field_at_every_point() {
        let field = FieldEval::new(Field::Blobs, 11);
        let (dims, origin, h) = ([7, 5, 9], [-1.0, -0.8, -1.2], [0.3, 0.4, 0.27]);
        let lattice = field.on_lattice(dims, origin, h).unwrap();
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let p = std::array::from_fn(|a| origin[a] + [i, j, k][a] as f64 * h[a]);
                    let (want, got) = (field.eval(p), lattice.at([i, j, k]));
                    assert!(
                        (want - got).abs() <= 1e-12 * want.max(1e-300),
                        "{want} {got}"
                    );
                }
            }
        }
        assert!(FieldEval::new(Field::Radial, 11)
            .on_lattice(dims, origin, h)
            .is_none());
    }

    #[test]
    fn sizes_and_specs_parse() {
        assert_eq!(parse_size("200k"), Some(200_000));
        assert_eq!(parse_size("1M"), Some(1_000_000));
        assert_eq!(parse_size("1.5m"), Some(1_500_000));
        assert_eq!(parse_size("5000"), Some(5000));
        assert_eq!(parse_size("0"), None);
        assert_eq!(parse_size("lots"), None);
        let s = parse_spec("box:200k:field=blobs:seed=3").unwrap();
        assert_eq!(
            (s.kind, s.target_tets, s.field, s.seed),
            (Kind::Box, 200_000, Field::Blobs, Some(3))
        );
        assert!(matches!(
            parse_spec("cube:1k"),
            Err(ErrorKind::Syntax { .. })
        ));
        assert!(matches!(
            parse_spec("box:1k:field=nope"),
            Err(ErrorKind::Syntax { .. })
        ));
        assert!(matches!(parse_spec("box:"), Err(ErrorKind::Syntax { .. })));
        assert!(is_spec("shell:1m") && !is_spec("spx") && !is_spec("C:/data/x.vtk"));
    }

    #[test]
    fn box_cells_hit_targets() {
        for t in [1_000, 5_000, 50_000, 200_000, 1_000_000, 20_000_000] {
            let c = box_cells(t);
            let n = 5 * c.iter().product::<usize>();
            assert!(
                ((n as f64) - t as f64).abs() / (t as f64) < 0.03,
                "{t}: {c:?} gives {n}"
            );
        }
        // Shape first, then count: within 25 % below 10 k tets, 10 % below 100 k, else 5 %.
        for (t, tolerance) in [
            (1_000, 0.25),
            (10_000, 0.10),
            (1_000_000, 0.05),
            (20_000_000, 0.05),
        ] {
            let (n, m) = shell_cells(t);
            let got = 36 * n * n * m;
            assert!(
                ((got as f64) - t as f64).abs() / (t as f64) < tolerance,
                "{t}: ({n},{m}) gives {got}"
            );
        }
    }

    #[test]
    fn marschner_lobb_range() {
        let f = FieldEval::new(Field::MarschnerLobb, 0);
        // ρ(0,0,-1) = (1 + 1 + α·2)/(2(1+α)) = 1; ρ at the top centre: (0 + α(1+cos 0))/(2.5) = 0.2
        assert!((f.eval([0.0, 0.0, -1.0]) - 1.0).abs() < 1e-12);
        assert!((f.eval([0.0, 0.0, 1.0]) - 0.2).abs() < 1e-12);
    }
}
