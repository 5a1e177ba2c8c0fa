//! The reconstruction kernel and its table of footprint slices (Grau & Tost §3.6: every slice
//! of the kernel footprint a slab can cut is precomputed and packed into one 2D table, instead
//! of scaling a single footprint per slab as Neophytou & Mueller do).
//!
//! Units: the kernel lives in *kernel units*, one unit = the grid spacing (the largest spacing
//! of an anisotropic grid). The kernel is a truncated Gaussian g(r) ∝ exp(−r²/2σ²) − exp(−R²/2σ²)
//! for r < R (continuous at R), normalised to ∫g = 1. With σ = 0.65 and R = 2 the sum of the
//! kernels on a unit lattice is 1 to within 0.7 % (the ripple of a sampled Gaussian falls as
//! exp(−2π²σ²); a wider σ loses more to the truncation), so splatting nearly reproduces a
//! constant field, and the sheets divide by the summed weight anyway; the paper does not name
//! its kernel.
//!
//! A slab is `thickness` kernel units deep. A voxel whose centre lies `delta` slabs behind the
//! slab's front plane (delta ∈ [−r, r+1), r = the kernel radius in slabs) contributes to that
//! slab's sheet the slice footprint T_delta(x, y) = (1/thickness) ∫_slab g(x, y, z) dz: the
//! kernel averaged over the slab depth, so that a sheet holds the slab's mean value. The table
//! samples delta at `subslices` rows per slab (rows 0 ..= (2r+1)·subslices, row q at
//! delta = q/subslices − r; shaders interpolate between rows) and (x, y) on `footprint`²
//! texels covering [−R, R]², each texel the average over 4×4 sub-samples (so the texel sum is
//! the integral, which the tests check).

/// The truncated Gaussian kernel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kernel {
    /// Radius R in kernel units (beyond it the kernel is 0).
    pub radius: f64,
    /// Gaussian σ in kernel units.
    pub sigma: f64,
    /// Normalisation: 1 / ∫ (exp(−r²/2σ²) − exp(−R²/2σ²)) over the ball.
    norm: f64,
}

/// σ of the kernel in grid spacings (see the module documentation).
pub const SIGMA: f64 = 0.65;

impl Kernel {
    pub fn new(radius: f64, sigma: f64) -> Kernel {
        let mut k = Kernel {
            radius,
            sigma,
            norm: 1.0,
        };
        // ∫_ball = 4π ∫_0^R (e(r) − e_R) r² dr, Simpson with many steps (smooth integrand).
        let n = 20_000;
        let h = radius / n as f64;
        let f = |r: f64| k.unnormalised(r) * r * r;
        let mut s = f(0.0) + f(radius);
        for i in 1..n {
            s += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        k.norm = 1.0 / (4.0 * std::f64::consts::PI * s * h / 3.0);
        k
    }

    fn edge(&self) -> f64 {
        (-self.radius * self.radius / (2.0 * self.sigma * self.sigma)).exp()
    }

    fn unnormalised(&self, r: f64) -> f64 {
        if r >= self.radius {
            0.0
        } else {
            (-r * r / (2.0 * self.sigma * self.sigma)).exp() - self.edge()
        }
    }

    /// The kernel at distance `r` from its centre (∫ over space = 1).
    pub fn value(&self, r: f64) -> f64 {
        self.unnormalised(r) * self.norm
    }

    /// ∫_{z0}^{z1} g(x, y, z) dz at distance ρ = √(x² + y²) from the axis, in closed form.
    pub fn z_integral(&self, rho: f64, z0: f64, z1: f64) -> f64 {
        let r2 = self.radius * self.radius - rho * rho;
        if r2 <= 0.0 {
            return 0.0;
        }
        let zm = r2.sqrt();
        let (a, b) = (z0.max(-zm), z1.min(zm));
        if b <= a {
            return 0.0;
        }
        let s = self.sigma;
        let sq2 = s * std::f64::consts::SQRT_2;
        let gauss = (-rho * rho / (2.0 * s * s)).exp()
            * s
            * (std::f64::consts::PI / 2.0).sqrt()
            * (erf(b / sq2) - erf(a / sq2));
        (gauss - self.edge() * (b - a)) * self.norm
    }

    /// The kernel projected along a line: ∫ g dz over all z (the image of one voxel).
    pub fn projection(&self, rho: f64) -> f64 {
        self.z_integral(rho, -self.radius, self.radius)
    }

    /// ∫ over all x, y and z ∈ [z0, z1] of the kernel, by the disk integral in closed form and
    /// Simpson's rule in z (an independent route to what the footprint table must sum to).
    pub fn slab_integral(&self, z0: f64, z1: f64) -> f64 {
        let (a, b) = (z0.max(-self.radius), z1.min(self.radius));
        if b <= a {
            return 0.0;
        }
        let s2 = self.sigma * self.sigma;
        let e_r = self.edge();
        let disk = |z: f64| {
            let rr = self.radius * self.radius - z * z;
            if rr <= 0.0 {
                return 0.0;
            }
            2.0 * std::f64::consts::PI
                * (s2 * ((-z * z / (2.0 * s2)).exp() - e_r) - e_r * rr / 2.0)
                * self.norm
        };
        let n = 4000;
        let h = (b - a) / n as f64;
        let mut s = disk(a) + disk(b);
        for i in 1..n {
            s += disk(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        s * h / 3.0
    }
}

/// erf(x) to ~1e-12 (Abramowitz & Stegun 7.1.5 series for |x| < 3, asymptotic continued
/// fraction beyond; std has no erf).
pub fn erf(x: f64) -> f64 {
    let ax = x.abs();
    let v = if ax < 3.0 {
        // erf x = 2/√π Σ (−1)^n x^(2n+1) / (n! (2n+1))
        let mut term = ax;
        let mut sum = ax;
        let x2 = ax * ax;
        let mut n = 0.0;
        while term.abs() > 1e-17 * sum.abs() {
            n += 1.0;
            term *= -x2 / n;
            sum += term / (2.0 * n + 1.0);
            if n > 200.0 {
                break;
            }
        }
        2.0 / std::f64::consts::PI.sqrt() * sum
    } else {
        // erfc x = exp(−x²)/√π · 1/(x + 1/2/(x + 1/(x + 3/2/(x + …)))) (Lentz-free, 60 levels).
        let mut f = ax;
        for k in (1..60).rev() {
            f = ax + (k as f64 / 2.0) / f;
        }
        1.0 - (-ax * ax).exp() / (std::f64::consts::PI.sqrt() * f)
    };
    v.copysign(x)
}

/// The footprint slices of one kernel for one slab thickness (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct FootprintTable {
    pub kernel: Kernel,
    /// Slab thickness in kernel units.
    pub thickness: f64,
    /// Kernel radius in slabs: a slab gathers the buckets i − r … i + r.
    pub radius_slabs: u32,
    /// Rows per slab of voxel offset.
    pub subslices: u32,
    /// Texels per side of one slice.
    pub footprint: u32,
    /// `rows() × footprint²` values, row-major per slice, y-major within a slice.
    pub values: Vec<f32>,
}

/// Sub-samples per texel side when averaging a texel.
const TEXEL_SUBSAMPLES: usize = 4;

impl FootprintTable {
    pub fn new(kernel: Kernel, thickness: f64, subslices: u32, footprint: u32) -> FootprintTable {
        let radius_slabs = (kernel.radius / thickness - 1e-9).ceil().max(0.0) as u32;
        let rows = (2 * radius_slabs + 1) * subslices + 1;
        let f = footprint as usize;
        let texel = 2.0 * kernel.radius / f as f64;
        let mut values = Vec::with_capacity(rows as usize * f * f);
        for q in 0..rows {
            let delta = q as f64 / subslices as f64 - radius_slabs as f64;
            let (z0, z1) = (-delta * thickness, (1.0 - delta) * thickness);
            for ty in 0..f {
                for tx in 0..f {
                    let mut sum = 0.0;
                    for sy in 0..TEXEL_SUBSAMPLES {
                        for sx in 0..TEXEL_SUBSAMPLES {
                            let sub = |t: usize, s: usize| {
                                -kernel.radius
                                    + texel
                                        * (t as f64 + (s as f64 + 0.5) / TEXEL_SUBSAMPLES as f64)
                            };
                            let (x, y) = (sub(tx, sx), sub(ty, sy));
                            sum += kernel.z_integral((x * x + y * y).sqrt(), z0, z1);
                        }
                    }
                    values.push(
                        (sum / (TEXEL_SUBSAMPLES * TEXEL_SUBSAMPLES) as f64 / thickness) as f32,
                    );
                }
            }
        }
        FootprintTable {
            kernel,
            thickness,
            radius_slabs,
            subslices,
            footprint,
            values,
        }
    }

    pub fn rows(&self) -> u32 {
        (2 * self.radius_slabs + 1) * self.subslices + 1
    }

    /// Area of one texel in kernel units².
    pub fn texel_area(&self) -> f64 {
        let t = 2.0 * self.kernel.radius / self.footprint as f64;
        t * t
    }

    /// ∫∫ of slice `row` times the thickness: the kernel's integral over that slab.
    pub fn slice_integral(&self, row: u32) -> f64 {
        let n = (self.footprint * self.footprint) as usize;
        let s: f64 = self.values[row as usize * n..(row as usize + 1) * n]
            .iter()
            .map(|&v| v as f64)
            .sum();
        s * self.texel_area() * self.thickness
    }

    /// The table as `splat_cs` reads it: each slice bordered by a texel of zeros on every side
    /// ((footprint + 2)² values a slice), which stands for the zero outside the table, so the
    /// shader's lookup needs no bounds test.
    pub fn bordered(&self) -> Vec<f32> {
        let n = self.footprint as usize;
        let side = n + 2;
        let mut out = vec![0.0f32; self.rows() as usize * side * side];
        for (q, slice) in self.values.chunks_exact(n * n).enumerate() {
            for (ty, row) in slice.chunks_exact(n).enumerate() {
                let o = q * side * side + (ty + 1) * side + 1;
                out[o..o + n].copy_from_slice(row);
            }
        }
        out
    }

    /// The value the shader computes: slice interpolated linearly in `delta`, bilinearly in
    /// (x, y) kernel units, 0 outside the table (CPU twin of `footprint()` in `splat.wgsl`).
    pub fn sample(&self, delta: f64, x: f64, y: f64) -> f64 {
        let rows = self.rows();
        let qf = ((delta + self.radius_slabs as f64) * self.subslices as f64)
            .clamp(0.0, (rows - 1) as f64);
        let q0 = (qf.floor() as u32).min(rows - 2);
        let fq = qf - q0 as f64;
        let f = self.footprint as f64;
        let u = (x + self.kernel.radius) / (2.0 * self.kernel.radius) * f - 0.5;
        let v = (y + self.kernel.radius) / (2.0 * self.kernel.radius) * f - 0.5;
        let tile = |q: u32| {
            let n = self.footprint as i64;
            let at = |tx: i64, ty: i64| -> f64 {
                if tx < 0 || ty < 0 || tx >= n || ty >= n {
                    return 0.0;
                }
                self.values[(q as i64 * n * n + ty * n + tx) as usize] as f64
            };
            let (x0, y0) = (u.floor(), v.floor());
            let (fx, fy) = (u - x0, v - y0);
            let (x0, y0) = (x0 as i64, y0 as i64);
            (at(x0, y0) * (1.0 - fx) + at(x0 + 1, y0) * fx) * (1.0 - fy)
                + (at(x0, y0 + 1) * (1.0 - fx) + at(x0 + 1, y0 + 1) * fx) * fy
        };
        tile(q0) * (1.0 - fq) + tile(q0 + 1) * fq
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erf_matches_known_values() {
        for (x, want) in [
            (0.0, 0.0),
            (0.5, 0.520_499_877_813_046_5),
            (1.0, 0.842_700_792_949_714_9),
            (2.0, 0.995_322_265_018_952_7),
            (3.5, 0.999_999_256_901_627_7),
            (-1.0, -0.842_700_792_949_714_9),
        ] {
            assert!((erf(x) - want).abs() < 1e-12, "erf({x}) = {}", erf(x));
        }
    }

    #[test]
    fn kernel_integrates_to_one_and_tiles_a_lattice() {
        let k = Kernel::new(2.0, SIGMA);
        assert!((k.slab_integral(-3.0, 3.0) - 1.0).abs() < 1e-9);
        // Partition of unity on the unit lattice (what lets splatting reproduce a constant).
        for p in [[0.0, 0.0, 0.0], [0.5, 0.5, 0.5], [0.3, 0.1, 0.7]] {
            let mut s = 0.0;
            for i in -3i32..=3 {
                for j in -3i32..=3 {
                    for l in -3i32..=3 {
                        let d = [i as f64 - p[0], j as f64 - p[1], l as f64 - p[2]];
                        s += k.value((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
                    }
                }
            }
            assert!((s - 1.0).abs() < 7e-3, "lattice sum at {p:?}: {s}");
        }
    }

    /// tests: the slice footprints of one voxel sum to the kernel's integral over
    /// each slab, and over all the slabs it touches to 1, within 1e-4.
    #[test]
    fn slice_footprints_sum_to_the_slab_integrals() {
        for (radius, thickness) in [(2.0, 1.0), (2.0, 0.5), (1.5, 1.0)] {
            let k = Kernel::new(radius, SIGMA);
            let t = FootprintTable::new(k, thickness, 8, 32);
            let r = t.radius_slabs as i64;
            for q in 0..t.rows() {
                let delta = q as f64 / 8.0 - r as f64;
                let want = k.slab_integral(-delta * thickness, (1.0 - delta) * thickness);
                let got = t.slice_integral(q);
                assert!((got - want).abs() < 1e-4, "row {q}: {got} vs {want}");
            }
            // A voxel at offset f in its own slab: slabs i − r … i + r see it at f + r … f − r.
            for sub in 0..8u32 {
                let total: f64 = (-r..=r)
                    .map(|j| t.slice_integral(((j + r) as u32) * 8 + sub))
                    .sum();
                assert!((total - 1.0).abs() < 1e-4, "offset {sub}/8: {total}");
            }
        }
    }
}
