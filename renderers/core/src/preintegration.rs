//! Exact ray-segment integration through the piecewise-linear transfer function, and the
//! pre-integration tables built from it (all arithmetic in f64; tables stored as f32).
//!
//! Optical model (Williams & Max 1992, emission–absorption): along a segment of length D (in
//! units of [`Optics::length_unit`]) the normalised scalar goes linearly from `s_front` to
//! `s_back`; emission is κ(s)·c(s), absorption κ(s). The segment's premultiplied colour and
//! opacity are
//!
//! ```text
//! C = ∫₀ᴰ κ(s(x))·c(s(x))·T(x) dx,   α = 1 − T(D),   T(x) = exp(−∫₀ˣ κ(s(u)) du).
//! ```
//!
//! Splitting the segment at the transfer function's breakpoints makes κ and c linear in x on
//! every piece. For linear τ(x) and C(x) Moreland & Angel ("A Fast High Accuracy Volume
//! Renderer for Unstructured Data", IEEE VolVis 2004, §3 "partial pre-integration") show by
//! integrating by parts (κ·T = −dT/dx) that
//!
//! ```text
//! C = C_b·(ψ − ζ) + C_f·(1 − ψ),   α = 1 − ζ,   ζ = exp(−D·(τ_f + τ_b)/2),
//! ψ(τ_f·D, τ_b·D) = (1/D)∫₀ᴰ T(x) dx = ∫₀¹ exp(−τ_f·D·w − (τ_b − τ_f)·D·w²/2) dw,
//! ```
//!
//! so the whole problem reduces to the one two-argument function ψ, which this module
//! evaluates to ~1e-15 (8-point Gauss–Legendre on panels where the optical depth grows by 1).
//! The pieces are composited front to back. That is [`integrate_segment`], the workhorse of
//! the tables below and of the exact reference renderer.
//!
//! Tables (conventions of ARCHITECTURE.md): entry `i` of an axis of `n` entries stands for
//! s = i/(n−1) (and length = i/(n−1)·max_length); a GPU samples texel centres,
//! u = (s·(n−1) + ½)/n, which is linear interpolation between neighbouring entries; the CPU
//! `sample` methods here do exactly that (with exact, not fixed-point, weights).

// `!(x > 0.0)` is used on purpose: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use rayon::prelude::*;

use crate::transfer::{ColorPoint, KappaPoint, Optics, TransferFunction};

/// Premultiplied RGB and opacity of a segment, in f64.
pub type Rgba = [f64; 4];

/// Front-to-back compositing: `acc` is in front of `seg`.
#[inline]
pub fn composite_front_to_back(acc: &mut Rgba, seg: Rgba) {
    let t = 1.0 - acc[3];
    for k in 0..4 {
        acc[k] += t * seg[k];
    }
}

// ---------------------------------------------------------------------------------------------
// ψ
// ---------------------------------------------------------------------------------------------

/// Gauss–Legendre, 8 nodes on [−1, 1] (positive half; symmetric).
const GL8_X: [f64; 4] = [
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_3,
];
const GL8_W: [f64; 4] = [
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_3,
];

/// ψ(a, b) = ∫₀¹ exp(−a·w − (b − a)·w²/2) dw for optical depths a = τ_f·D ≥ 0, b = τ_b·D ≥ 0
/// (Moreland & Angel 2004, §3): the mean transparency of a segment whose extinction varies
/// linearly from τ_f to τ_b. ψ(0, 0) = 1; ψ → 0 as either argument → ∞. Accurate to ~1e-15
/// absolute.
pub fn psi(a: f64, b: f64) -> f64 {
    let (a, b) = (a.max(0.0), b.max(0.0));
    if a.is_infinite() || b.is_infinite() {
        return 0.0;
    }
    // The exponent E(w) = a·w + (b − a)·w²/2 increases on [0, 1] (E' lies between a and b).
    // Panels end where E crosses the next integer, so E changes by at most 1 on each and
    // |E''|·Δw² ≤ 2: there 8-point Gauss–Legendre is exact to rounding (error term
    // ~ f⁽¹⁶⁾/16!·(8!)⁴/(17·(16!)²) < 1e-16 of the panel's integral). Past E = 40 the
    // integrand is below e⁻⁴⁰ ≈ 4e-18 and the tail is dropped.
    let e_end = 0.5 * (a + b);
    let k = (b - a) * 0.5;
    let w_at = |e: f64| -> f64 {
        if e >= e_end {
            return 1.0;
        }
        // Root in [0, 1] of k·w² + a·w − e = 0, in the cancellation-free form.
        let disc = (a * a + 4.0 * k * e).max(0.0);
        let den = a + disc.sqrt();
        if den > 0.0 {
            (2.0 * e / den).min(1.0)
        } else {
            1.0
        }
    };
    let f = |w: f64| (-(a * w + k * w * w)).exp();
    let panels = e_end.min(40.0).ceil().max(1.0) as usize;
    let mut sum = 0.0;
    let mut w0 = 0.0;
    for p in 1..=panels {
        let w1 = if p == panels && e_end <= 40.0 {
            1.0
        } else {
            w_at(p as f64)
        };
        let (c, h) = (0.5 * (w0 + w1), 0.5 * (w1 - w0));
        let mut s = 0.0;
        for i in 0..4 {
            let dx = h * GL8_X[i];
            s += GL8_W[i] * (f(c - dx) + f(c + dx));
        }
        sum += h * s;
        w0 = w1;
    }
    sum
}

/// The contribution of a segment of length `d` (in length units) along which extinction and
/// colour are linear: τ_f → τ_b and c_f → c_b (Moreland & Angel 2004, §3), with ψ given.
#[inline]
pub fn linear_segment_with_psi(
    psi_value: f64,
    tau_f: f64,
    tau_b: f64,
    c_f: [f64; 3],
    c_b: [f64; 3],
    d: f64,
) -> Rgba {
    let zeta = (-0.5 * d * (tau_f + tau_b)).exp();
    let wf = 1.0 - psi_value;
    let wb = psi_value - zeta;
    [
        c_b[0] * wb + c_f[0] * wf,
        c_b[1] * wb + c_f[1] * wf,
        c_b[2] * wb + c_f[2] * wf,
        1.0 - zeta,
    ]
}

/// Exact contribution of a segment on which κ and c are linear.
#[inline]
pub fn linear_segment(tau_f: f64, tau_b: f64, c_f: [f64; 3], c_b: [f64; 3], d: f64) -> Rgba {
    if !(d > 0.0) {
        return [0.0; 4];
    }
    linear_segment_with_psi(psi(tau_f * d, tau_b * d), tau_f, tau_b, c_f, c_b, d)
}

// ---------------------------------------------------------------------------------------------
// Exact segment integration through a piecewise-linear transfer function
// ---------------------------------------------------------------------------------------------

/// Values at `s0` and `s1` of the linear piece of a piecewise-linear function that contains
/// the open interval between them (so a step — two points at the same s — is evaluated from
/// the correct side).
#[inline]
fn piece_values<P: Copy, const N: usize>(
    pts: &[P],
    key: impl Fn(&P) -> f64,
    val: impl Fn(&P) -> [f64; N],
    s0: f64,
    s1: f64,
) -> ([f64; N], [f64; N]) {
    let mid = 0.5 * (s0 + s1);
    let i = pts.partition_point(|p| key(p) <= mid);
    if i == 0 {
        let v = val(&pts[0]);
        return (v, v);
    }
    if i == pts.len() {
        let v = val(&pts[pts.len() - 1]);
        return (v, v);
    }
    let (a, b) = (&pts[i - 1], &pts[i]);
    let (sa, sb) = (key(a), key(b));
    let (va, vb) = (val(a), val(b));
    let w = sb - sa;
    if !(w > 0.0) {
        return (vb, vb);
    }
    let at = |s: f64| {
        let t = (s - sa) / w;
        std::array::from_fn(|k| va[k] + t * (vb[k] - va[k]))
    };
    (at(s0), at(s1))
}

/// A transfer function prepared for repeated exact segment integration (breakpoints merged
/// and sorted once). [`integrate_segment`] is the one-shot convenience.
#[derive(Debug, Clone)]
pub struct SegmentIntegrator<'a> {
    tf: &'a TransferFunction,
    breaks: Vec<f64>,
}

impl<'a> SegmentIntegrator<'a> {
    pub fn new(tf: &'a TransferFunction) -> SegmentIntegrator<'a> {
        SegmentIntegrator {
            tf,
            breaks: tf.breakpoints(),
        }
    }

    fn piece(&self, s0: f64, s1: f64, d: f64) -> Rgba {
        let (k0, k1) = piece_values(&self.tf.kappa, |p: &KappaPoint| p.s, |p| [p.kappa], s0, s1);
        let (c0, c1) = piece_values(&self.tf.color, |p: &ColorPoint| p.s, |p| p.rgb, s0, s1);
        linear_segment(k0[0], k1[0], c0, c1, d)
    }

    /// Exact (to ~1e-14) premultiplied RGBA of a segment of `length` (in units of the
    /// optics' length unit) along which the normalised scalar goes linearly from `s_front` to
    /// `s_back`: split at every breakpoint strictly between the two, each piece integrated in
    /// closed form up to ψ, pieces composited front to back.
    pub fn integrate(&self, s_front: f64, s_back: f64, length: f64) -> Rgba {
        if !(length > 0.0) {
            return [0.0; 4];
        }
        let (lo, hi) = if s_front <= s_back {
            (s_front, s_back)
        } else {
            (s_back, s_front)
        };
        let first = self.breaks.partition_point(|&b| b <= lo);
        let last = self.breaks.partition_point(|&b| b < hi);
        if first >= last {
            return self.piece(s_front, s_back, length);
        }
        let inner = &self.breaks[first..last];
        let ds = s_back - s_front;
        let mut acc = [0.0; 4];
        let mut s_prev = s_front;
        let mut u_prev = 0.0;
        let mut step = |s_next: f64, u_next: f64, acc: &mut Rgba| {
            let seg = self.piece(s_prev, s_next, length * (u_next - u_prev));
            composite_front_to_back(acc, seg);
            s_prev = s_next;
            u_prev = u_next;
        };
        if ds > 0.0 {
            for &b in inner {
                step(b, (b - s_front) / ds, &mut acc);
            }
        } else {
            for &b in inner.iter().rev() {
                step(b, (b - s_front) / ds, &mut acc);
            }
        }
        step(s_back, 1.0, &mut acc);
        acc
    }
}

/// Exact contribution of one segment: see [`SegmentIntegrator::integrate`]. `length` is in
/// units of [`Optics::length_unit`].
pub fn integrate_segment(tf: &TransferFunction, s_front: f64, s_back: f64, length: f64) -> Rgba {
    SegmentIntegrator::new(tf).integrate(s_front, s_back, length)
}

// ---------------------------------------------------------------------------------------------
// Tables
// ---------------------------------------------------------------------------------------------

/// Linear interpolation coordinate of `x` ∈ [0, 1] on an axis of `n` entries, as a GPU's
/// linear filter at u = (x·(n−1) + ½)/n with clamp-to-edge computes it: (index, weight).
#[inline]
fn axis(x: f64, n: usize) -> (usize, f64) {
    if n < 2 {
        return (0, 0.0);
    }
    let f = (x * (n - 1) as f64).clamp(0.0, (n - 1) as f64);
    let i = (f.floor() as usize).min(n - 2);
    (i, f - i as f64)
}

fn lerp4(a: [f32; 4], b: [f32; 4], t: f64) -> [f64; 4] {
    std::array::from_fn(|k| a[k] as f64 + t * (b[k] as f64 - a[k] as f64))
}

fn to_f32(v: Rgba) -> [f32; 4] {
    v.map(|x| x as f32)
}

/// The full 3D pre-integration table of HAVS (Callahan et al. 2005, §3.3):
/// (s_front, s_back, length) → premultiplied RGBA. Entry `(il * n_s + isb) * n_s + isf`
/// holds the segment from s = isf/(n_s−1) to s = isb/(n_s−1) of world length
/// il/(n_l−1)·max_length_world.
#[derive(Debug, Clone, PartialEq)]
pub struct Table3d {
    pub n_s: usize,
    pub n_l: usize,
    /// World length of the last length entry (the longest segment the table covers).
    pub max_length_world: f64,
    /// The optics' length unit the table was built for (κ per this many world units).
    pub length_unit: f64,
    pub data: Vec<[f32; 4]>,
}

impl Table3d {
    /// HAVS' default resolution, 128³.
    pub const DEFAULT_SIZE: usize = 128;

    /// Builds the table with [`integrate_segment`] at every entry (rayon over length slices).
    pub fn build(optics: &Optics, n_s: usize, n_l: usize, max_length_world: f64) -> Table3d {
        let n_s = n_s.max(2);
        let n_l = n_l.max(2);
        let integ = SegmentIntegrator::new(&optics.tf);
        let unit = optics.length_unit;
        let mut data = vec![[0f32; 4]; n_s * n_s * n_l];
        data.par_chunks_mut(n_s * n_s)
            .enumerate()
            .for_each(|(il, slice)| {
                let len = il as f64 / (n_l - 1) as f64 * max_length_world / unit;
                for isb in 0..n_s {
                    for isf in 0..n_s {
                        let sf = isf as f64 / (n_s - 1) as f64;
                        let sb = isb as f64 / (n_s - 1) as f64;
                        slice[isb * n_s + isf] = to_f32(integ.integrate(sf, sb, len));
                    }
                }
            });
        Table3d {
            n_s,
            n_l,
            max_length_world,
            length_unit: unit,
            data,
        }
    }

    #[inline]
    pub fn index(&self, isf: usize, isb: usize, il: usize) -> usize {
        (il * self.n_s + isb) * self.n_s + isf
    }

    /// Trilinear sample as a GPU sampler returns it (texel centres, clamp to edge): lengths
    /// beyond `max_length_world` clamp to the last slice.
    pub fn sample(&self, s_front: f64, s_back: f64, length_world: f64) -> [f64; 4] {
        let (i, fi) = axis(s_front, self.n_s);
        let (j, fj) = axis(s_back, self.n_s);
        let l = if self.max_length_world > 0.0 {
            length_world / self.max_length_world
        } else {
            0.0
        };
        let (k, fk) = axis(l, self.n_l);
        let at = |a, b, c| self.data[self.index(a, b, c)];
        let plane = |k| {
            let x0 = lerp4(at(i, j, k), at(i + 1, j, k), fi);
            let x1 = lerp4(at(i, j + 1, k), at(i + 1, j + 1, k), fi);
            std::array::from_fn::<f64, 4, _>(|c| x0[c] + fj * (x1[c] - x0[c]))
        };
        let (p0, p1) = (plane(k), plane(k + 1));
        std::array::from_fn(|c| p0[c] + fk * (p1[c] - p0[c]))
    }

    /// Bytes of the table as uploaded (RGBA f32).
    pub fn bytes(&self) -> u64 {
        (self.data.len() * 16) as u64
    }
}

/// The 2D pre-integration table for a fixed segment length (Röttger et al. 2000; Engel et al.
/// 2001): (s_front, s_back) → RGBA, entry `isb * n_s + isf`. Used by tiled ray casting, whose
/// samples are a constant distance apart.
#[derive(Debug, Clone, PartialEq)]
pub struct Table2d {
    pub n_s: usize,
    pub length_world: f64,
    pub length_unit: f64,
    pub data: Vec<[f32; 4]>,
}

impl Table2d {
    pub fn build(optics: &Optics, n_s: usize, length_world: f64) -> Table2d {
        let n_s = n_s.max(2);
        let integ = SegmentIntegrator::new(&optics.tf);
        let len = length_world / optics.length_unit;
        let mut data = vec![[0f32; 4]; n_s * n_s];
        data.par_chunks_mut(n_s).enumerate().for_each(|(isb, row)| {
            let sb = isb as f64 / (n_s - 1) as f64;
            for (isf, e) in row.iter_mut().enumerate() {
                *e = to_f32(integ.integrate(isf as f64 / (n_s - 1) as f64, sb, len));
            }
        });
        Table2d {
            n_s,
            length_world,
            length_unit: optics.length_unit,
            data,
        }
    }

    /// Bilinear sample as a GPU sampler returns it.
    pub fn sample(&self, s_front: f64, s_back: f64) -> [f64; 4] {
        let (i, fi) = axis(s_front, self.n_s);
        let (j, fj) = axis(s_back, self.n_s);
        let at = |a: usize, b: usize| self.data[b * self.n_s + a];
        let x0 = lerp4(at(i, j), at(i + 1, j), fi);
        let x1 = lerp4(at(i, j + 1), at(i + 1, j + 1), fi);
        std::array::from_fn(|c| x0[c] + fj * (x1[c] - x0[c]))
    }
}

/// γ = τD/(τD + 1): maps an optical depth in [0, ∞) to [0, 1), the ψ table's coordinate
/// (Moreland & Angel 2004, §3.2).
#[inline]
pub fn psi_gamma(tau_d: f64) -> f64 {
    let x = tau_d.max(0.0);
    if x.is_infinite() {
        1.0
    } else {
        x / (x + 1.0)
    }
}

/// The partial pre-integration table of Moreland & Angel (2004): ψ(τ_f·D, τ_b·D) sampled on
/// γ_f, γ_b = i/(n−1), entry `data[ib * n + if]`. It does not depend on the transfer function.
/// At γ = 1 (infinite optical depth) ψ is its limit, 0.
#[derive(Debug, Clone, PartialEq)]
pub struct PsiTable {
    pub n: usize,
    pub data: Vec<f32>,
}

impl PsiTable {
    /// VTK's partial pre-integration uses 512² entries.
    pub const DEFAULT_SIZE: usize = 512;

    pub fn build(n: usize) -> PsiTable {
        let n = n.max(2);
        let depth = |i: usize| {
            let g = i as f64 / (n - 1) as f64;
            if i == n - 1 {
                f64::INFINITY
            } else {
                g / (1.0 - g)
            }
        };
        let mut data = vec![0f32; n * n];
        data.par_chunks_mut(n).enumerate().for_each(|(ib, row)| {
            let b = depth(ib);
            for (i_f, e) in row.iter_mut().enumerate() {
                *e = psi(depth(i_f), b) as f32;
            }
        });
        PsiTable { n, data }
    }

    /// Bilinear sample at (γ_f, γ_b), as a GPU sampler returns it.
    pub fn sample(&self, gamma_f: f64, gamma_b: f64) -> f64 {
        let (i, fi) = axis(gamma_f, self.n);
        let (j, fj) = axis(gamma_b, self.n);
        let at = |a: usize, b: usize| self.data[b * self.n + a] as f64;
        let x0 = at(i, j) + fi * (at(i + 1, j) - at(i, j));
        let x1 = at(i, j + 1) + fi * (at(i + 1, j + 1) - at(i, j + 1));
        x0 + fj * (x1 - x0)
    }

    /// What fragment PT computes per fragment: [`partial_preintegration_segment`] with ψ
    /// looked up in this table instead of evaluated.
    pub fn segment(&self, tf: &TransferFunction, s_f: f64, s_b: f64, length: f64) -> Rgba {
        if !(length > 0.0) {
            return [0.0; 4];
        }
        let (tau_f, tau_b) = (tf.kappa_at(s_f), tf.kappa_at(s_b));
        let p = self.sample(psi_gamma(tau_f * length), psi_gamma(tau_b * length));
        linear_segment_with_psi(p, tau_f, tau_b, tf.color_at(s_f), tf.color_at(s_b), length)
    }
}

/// Partial pre-integration of one segment (Moreland & Angel 2004): κ and c are taken at the
/// two ends only and assumed linear in between, C = C_b(ψ − ζ) + C_f(1 − ψ), α = 1 − ζ. Exact
/// when no breakpoint of the transfer function lies strictly between `s_f` and `s_b`; an
/// approximation otherwise. ψ is evaluated exactly here; [`PsiTable::segment`] is the table
/// lookup a GPU performs. `length` is in length units.
pub fn partial_preintegration_segment(
    tf: &TransferFunction,
    s_f: f64,
    s_b: f64,
    length: f64,
) -> Rgba {
    linear_segment(
        tf.kappa_at(s_f),
        tf.kappa_at(s_b),
        tf.color_at(s_f),
        tf.color_at(s_b),
        length,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SplitMix64: a deterministic generator for test points.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Direct numerical integration of the ray ODE: `steps` midpoint steps, each step's
    /// opacity 1 − exp(−κ(s_mid)·h) and colour c(s_mid)·that opacity, composited front to back.
    fn ode_segment(tf: &TransferFunction, sf: f64, sb: f64, length: f64, steps: usize) -> Rgba {
        let h = length / steps as f64;
        let mut acc = [0.0; 4];
        for i in 0..steps {
            let s = sf + (sb - sf) * (i as f64 + 0.5) / steps as f64;
            let a = 1.0 - (-tf.kappa_at(s) * h).exp();
            let c = tf.color_at(s);
            composite_front_to_back(&mut acc, [c[0] * a, c[1] * a, c[2] * a, a]);
        }
        acc
    }

    fn max_diff(a: Rgba, b: Rgba) -> f64 {
        (0..4).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max)
    }

    /// A transfer function with a colour step (equal s) where κ = 0 (so a midpoint ODE can
    /// still resolve it), close breakpoints and a narrow κ spike.
    fn spiky() -> TransferFunction {
        TransferFunction {
            name: "spiky".into(),
            color: vec![
                ColorPoint {
                    s: 0.0,
                    rgb: [1.0, 0.0, 0.0],
                },
                ColorPoint {
                    s: 0.2,
                    rgb: [0.0, 1.0, 0.0],
                },
                ColorPoint {
                    s: 0.2,
                    rgb: [0.0, 0.0, 1.0],
                },
                ColorPoint {
                    s: 0.41,
                    rgb: [1.0, 1.0, 1.0],
                },
                ColorPoint {
                    s: 1.0,
                    rgb: [0.2, 0.5, 0.9],
                },
            ],
            kappa: vec![
                KappaPoint { s: 0.1, kappa: 0.0 },
                KappaPoint { s: 0.3, kappa: 0.0 },
                KappaPoint {
                    s: 0.5,
                    kappa: 40.0,
                },
                KappaPoint {
                    s: 0.52,
                    kappa: 1.0,
                },
                KappaPoint { s: 0.9, kappa: 8.0 },
            ],
        }
    }

    fn optics(tf: TransferFunction) -> Optics {
        Optics {
            tf,
            scalar_min: 0.0,
            scalar_max: 1.0,
            length_unit: 2.0,
        }
    }

    #[test]
    fn psi_closed_forms_and_limits() {
        assert!((psi(0.0, 0.0) - 1.0).abs() < 1e-15);
        for a in [1e-6f64, 0.01, 0.5, 1.0, 3.0, 15.9, 16.1, 100.0, 1e4] {
            // Constant extinction: ψ = (1 − e^(−a))/a.
            let exact = -(-a).exp_m1() / a;
            assert!(
                (psi(a, a) - exact).abs() < 1e-14,
                "a={a}: {} vs {exact}",
                psi(a, a)
            );
        }
        // Zero at the front, b at the back: ∫₀¹ e^(−b w²/2) dw = √(π/2b)·erf(√(b/2)); for
        // b = 200 erf(10) = 1 to double precision.
        assert!((psi(0.0, 200.0) - (std::f64::consts::PI / 400.0).sqrt()).abs() < 1e-14);
        assert_eq!(psi(f64::INFINITY, 1.0), 0.0);
        assert_eq!(psi(1.0, f64::INFINITY), 0.0);
    }

    #[test]
    fn psi_agrees_with_dense_simpson() {
        let mut rng = Rng(7);
        for _ in 0..60 {
            let a = (rng.next() * 12.0 - 6.0).exp();
            let b = (rng.next() * 12.0 - 6.0).exp();
            let n = 200_000;
            let f = |w: f64| (-(a * w + 0.5 * (b - a) * w * w)).exp();
            let h = 1.0 / n as f64;
            let mut s = f(0.0) + f(1.0);
            for i in 1..n {
                s += if i % 2 == 1 { 4.0 } else { 2.0 } * f(i as f64 * h);
            }
            let simpson = s * h / 3.0;
            assert!(
                (psi(a, b) - simpson).abs() < 1e-11,
                "a={a} b={b}: {} vs {simpson}",
                psi(a, b)
            );
        }
    }

    #[test]
    fn constant_kappa_and_colour_is_analytic() {
        let tf = TransferFunction {
            name: "const".into(),
            color: vec![ColorPoint {
                s: 0.5,
                rgb: [0.25, 0.5, 1.0],
            }],
            kappa: vec![KappaPoint { s: 0.5, kappa: 3.0 }],
        };
        for (sf, sb, l) in [
            (0.0, 1.0, 0.7),
            (0.3, 0.3, 2.0),
            (1.0, 0.0, 1e-4),
            (0.2, 0.9, 20.0),
        ] {
            let alpha = 1.0 - (-3.0f64 * l).exp();
            let got = integrate_segment(&tf, sf, sb, l);
            let want = [0.25 * alpha, 0.5 * alpha, alpha, alpha];
            assert!(max_diff(got, want) < 1e-14, "{got:?} vs {want:?}");
        }
        assert_eq!(integrate_segment(&tf, 0.0, 1.0, 0.0), [0.0; 4]);
    }

    #[test]
    fn colour_step_is_integrated_from_the_correct_side() {
        // Red below s = 0.5, blue above, κ = 2: the front half is red, the back half blue.
        let tf = TransferFunction {
            name: "step".into(),
            color: vec![
                ColorPoint {
                    s: 0.5,
                    rgb: [1.0, 0.0, 0.0],
                },
                ColorPoint {
                    s: 0.5,
                    rgb: [0.0, 0.0, 1.0],
                },
            ],
            kappa: vec![KappaPoint { s: 0.0, kappa: 2.0 }],
        };
        let d = 0.8;
        let half = 1.0 - (-2.0 * d / 2.0f64).exp();
        let fwd = integrate_segment(&tf, 0.0, 1.0, d);
        let want = [
            half,
            0.0,
            (1.0 - half) * half,
            1.0 - (1.0 - half) * (1.0 - half),
        ];
        assert!(max_diff(fwd, want) < 1e-14, "{fwd:?} vs {want:?}");
        let back = integrate_segment(&tf, 1.0, 0.0, d);
        let want = [(1.0 - half) * half, 0.0, half, want[3]];
        assert!(max_diff(back, want) < 1e-14, "{back:?} vs {want:?}");
    }

    #[test]
    fn integrate_segment_agrees_with_the_ray_ode() {
        let mut rng = Rng(11);
        let tfs = [
            TransferFunction::preset("low-opacity").unwrap(),
            TransferFunction::preset("high-opacity").unwrap(),
            spiky(),
        ];
        let mut worst: f64 = 0.0;
        for tf in &tfs {
            for _ in 0..25 {
                let (sf, sb) = (rng.next() * 1.2 - 0.1, rng.next() * 1.2 - 0.1);
                let l = rng.next() * 0.5;
                let e = max_diff(
                    integrate_segment(tf, sf, sb, l),
                    ode_segment(tf, sf, sb, l, 100_000),
                );
                worst = worst.max(e);
            }
            // Both directions across the colour step and the κ spike.
            for (sf, sb) in [(0.35, 0.6), (0.6, 0.35), (0.4, 0.4), (0.0, 1.0)] {
                let e = max_diff(
                    integrate_segment(tf, sf, sb, 0.3),
                    ode_segment(tf, sf, sb, 0.3, 100_000),
                );
                worst = worst.max(e);
            }
        }
        eprintln!("integrate_segment vs ODE: worst {worst:e}");
        assert!(worst < 1e-8, "worst difference {worst:e}");
    }

    #[test]
    fn table3d_entries_and_samples_agree_with_direct_integration() {
        let o = optics(TransferFunction::preset("low-opacity").unwrap());
        let (n_s, n_l, maxl) = (33, 17, 0.4);
        let t = Table3d::build(&o, n_s, n_l, maxl);
        assert_eq!(t.data.len(), n_s * n_s * n_l);
        let mut rng = Rng(3);
        // Entries: exact up to f32 storage.
        for _ in 0..40 {
            let (i, j, k) = (
                (rng.next() * n_s as f64) as usize,
                (rng.next() * n_s as f64) as usize,
                (rng.next() * n_l as f64) as usize,
            );
            let (sf, sb, lw) = (i as f64 / 32.0, j as f64 / 32.0, k as f64 / 16.0 * maxl);
            let ode = ode_segment(&o.tf, sf, sb, lw / o.length_unit, 100_000);
            let e = t.data[t.index(i, j, k)];
            assert!(
                max_diff(e.map(|x| x as f64), ode) < 1e-6,
                "entry ({i},{j},{k})"
            );
            // Sampling exactly at an entry returns it.
            assert!(max_diff(t.sample(sf, sb, lw), e.map(|x| x as f64)) < 1e-7);
        }
        // Between entries: trilinear interpolation error of a 33×33×17 table (low opacity).
        let mut worst: f64 = 0.0;
        for _ in 0..200 {
            let (sf, sb, lw) = (rng.next(), rng.next(), rng.next() * maxl);
            let ode = ode_segment(&o.tf, sf, sb, lw / o.length_unit, 20_000);
            worst = worst.max(max_diff(t.sample(sf, sb, lw), ode));
        }
        assert!(worst < 2e-3, "interpolation error {worst:e}");
        // Longer segments than the table covers clamp to the last slice.
        assert_eq!(t.sample(0.3, 0.6, 10.0 * maxl), t.sample(0.3, 0.6, maxl));
    }

    #[test]
    fn table2d_agrees_with_direct_integration() {
        let o = optics(spiky());
        let t = Table2d::build(&o, 257, 0.05);
        let mut rng = Rng(5);
        for _ in 0..40 {
            let (i, j) = ((rng.next() * 257.0) as usize, (rng.next() * 257.0) as usize);
            let ode = ode_segment(&o.tf, i as f64 / 256.0, j as f64 / 256.0, 0.025, 100_000);
            assert!(max_diff(t.data[j * 257 + i].map(|x| x as f64), ode) < 1e-6);
        }
        let mut worst: f64 = 0.0;
        for _ in 0..400 {
            let (sf, sb) = (rng.next(), rng.next());
            worst = worst.max(max_diff(
                t.sample(sf, sb),
                ode_segment(&o.tf, sf, sb, 0.025, 20_000),
            ));
        }
        // The κ spike (0 → 40 → 1 within 0.04 of s) is the worst case for a 257² table.
        assert!(worst < 5e-3, "interpolation error {worst:e}");
    }

    #[test]
    fn psi_table_agrees_with_direct_integration() {
        let n = 512;
        let t = PsiTable::build(n);
        let mut rng = Rng(9);
        let simpson = |a: f64, b: f64| {
            let m = 100_000;
            let f = |w: f64| (-(a * w + 0.5 * (b - a) * w * w)).exp();
            let h = 1.0 / m as f64;
            let mut s = f(0.0) + f(1.0);
            for i in 1..m {
                s += if i % 2 == 1 { 4.0 } else { 2.0 } * f(i as f64 * h);
            }
            s * h / 3.0
        };
        for _ in 0..30 {
            let (i, j) = (
                (rng.next() * (n - 1) as f64) as usize,
                (rng.next() * (n - 1) as f64) as usize,
            );
            let d = |k: usize| {
                let g = k as f64 / (n - 1) as f64;
                g / (1.0 - g)
            };
            assert!((t.data[j * n + i] as f64 - simpson(d(i), d(j))).abs() < 1e-6);
        }
        assert_eq!(t.data[n * n - 1], 0.0);
        let mut worst: f64 = 0.0;
        for _ in 0..300 {
            let (a, b) = (
                (rng.next() * 10.0 - 5.0).exp(),
                (rng.next() * 10.0 - 5.0).exp(),
            );
            worst = worst.max((t.sample(psi_gamma(a), psi_gamma(b)) - psi(a, b)).abs());
        }
        eprintln!("ψ table (512²) interpolation error {worst:e}");
        assert!(worst < 2e-4, "ψ table interpolation error {worst:e}");
    }

    #[test]
    fn partial_preintegration_exact_for_linear_and_close_otherwise() {
        // Linear κ and colour over the whole range: partial pre-integration is exact.
        let linear = TransferFunction {
            name: "lin".into(),
            color: vec![
                ColorPoint {
                    s: 0.0,
                    rgb: [1.0, 0.2, 0.0],
                },
                ColorPoint {
                    s: 1.0,
                    rgb: [0.0, 0.4, 1.0],
                },
            ],
            kappa: vec![
                KappaPoint { s: 0.0, kappa: 0.5 },
                KappaPoint {
                    s: 1.0,
                    kappa: 30.0,
                },
            ],
        };
        let table = PsiTable::build(512);
        let mut rng = Rng(13);
        for _ in 0..100 {
            let (sf, sb, l) = (rng.next(), rng.next(), rng.next() * 0.3);
            let exact = integrate_segment(&linear, sf, sb, l);
            assert!(max_diff(partial_preintegration_segment(&linear, sf, sb, l), exact) < 1e-13);
            assert!(max_diff(table.segment(&linear, sf, sb, l), exact) < 2e-4);
        }
        // The low-opacity preset over tet-sized segments (≤ 5% of the diagonal): assuming κ and
        // c linear between the ends misses the breakpoints in between. Over any scalar range
        // the colour can be off by a few percent (a blue→red segment skips the green of the
        // rainbow); over the ranges a tet typically spans (|Δs| ≤ 0.05) below 3e-3
        // (measured: 3.2e-2 and 1.6e-3).
        let tf = TransferFunction::preset("low-opacity").unwrap();
        let (mut worst, mut worst_small): (f64, f64) = (0.0, 0.0);
        for _ in 0..4000 {
            let (sf, l) = (rng.next(), rng.next() * 0.05);
            let sb = if rng.next() < 0.5 {
                rng.next()
            } else {
                (sf + 0.1 * rng.next() - 0.05).clamp(0.0, 1.0)
            };
            let e = max_diff(
                partial_preintegration_segment(&tf, sf, sb, l),
                integrate_segment(&tf, sf, sb, l),
            );
            worst = worst.max(e);
            if (sb - sf).abs() <= 0.05 {
                worst_small = worst_small.max(e);
            }
        }
        eprintln!(
            "partial pre-integration error: {worst:e} (any Δs), {worst_small:e} (|Δs| ≤ 0.05)"
        );
        assert!(worst < 5e-2, "partial pre-integration error {worst:e}");
        assert!(
            worst_small < 3e-3,
            "partial pre-integration error {worst_small:e}"
        );
    }
}
