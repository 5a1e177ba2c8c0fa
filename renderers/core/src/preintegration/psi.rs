// ---------------------------------------------------------------------------------------------
// ψ
// ---------------------------------------------------------------------------------------------

use super::Rgba;

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
