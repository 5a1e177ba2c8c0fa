//! Random numbers and fields: a counter-based SplitMix64 hash and the analytic point fields.

use std::f64::consts::PI;

use super::Field;

/// SplitMix64 finaliser (Steele et al. 2014): a high-quality 64-bit mix.
fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Uniform in [0, 1) from (seed, stream, index), independent of evaluation order.
pub(super) fn rand01(seed: u64, stream: u64, index: u64) -> f64 {
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
