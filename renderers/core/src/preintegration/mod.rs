//! Exact ray-segment integration through the piecewise-linear transfer function, and the
//! pre-integration tables built from it (all arithmetic in f64; tables stored as f32).
//!
//! Optical model (Williams & Max 1992, emission–absorption): along a segment of length D (in
//! units of [`Optics::length_unit`](crate::transfer::Optics::length_unit)) the normalised
//! scalar goes linearly from `s_front` to `s_back`; emission is κ(s)·c(s), absorption κ(s). The
//! segment's premultiplied colour and opacity are
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
//!
//! `psi.rs` ψ and the linear segment, `segment.rs` exact integration through the transfer
//! function, `tables.rs` the 3D, 2D and ψ tables and partial pre-integration.

// `!(x > 0.0)` is used on purpose: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod psi;
mod segment;
mod tables;

pub use psi::{linear_segment, linear_segment_with_psi, psi};
pub use segment::{integrate_segment, SegmentIntegrator};
pub use tables::{partial_preintegration_segment, psi_gamma, PsiTable, Table2d, Table3d};

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

#[cfg(test)]
mod tests;
