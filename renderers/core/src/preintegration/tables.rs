// ---------------------------------------------------------------------------------------------
// Tables
// ---------------------------------------------------------------------------------------------

use rayon::prelude::*;

use super::{linear_segment, linear_segment_with_psi, psi, Rgba, SegmentIntegrator};
use crate::transfer::{Optics, TransferFunction};

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

    /// Builds the table with [`integrate_segment`](super::integrate_segment) at every
    /// entry (rayon over length slices).
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
