//! ψ, the segment integrator and the tables against closed forms and brute-force quadrature.

use super::*;
use crate::transfer::{ColorPoint, KappaPoint, Optics, TransferFunction};

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
    eprintln!("partial pre-integration error: {worst:e} (any Δs), {worst_small:e} (|Δs| ≤ 0.05)");
    assert!(worst < 5e-2, "partial pre-integration error {worst:e}");
    assert!(
        worst_small < 3e-3,
        "partial pre-integration error {worst_small:e}"
    );
}
