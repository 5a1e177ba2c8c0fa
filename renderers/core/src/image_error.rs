//! The one image error of tetbench: RMSE and PSNR of a rendering against a reference, plus the
//! maximum absolute error and the share of visibly wrong pixels. The harness's result rows
//! (`harness::results::metrics`, which re-exports this module) and every test that compares two images
//! (`tests/*_vs_reference.rs`, `renderers/*/tests/`) call [`compare`] / [`psnr`], so a PSNR
//! in a test means the same as a PSNR in `results.csv`.
//!
//! What is measured:
//! - Images are premultiplied, linear-light RGBA over a black background; each channel is
//!   clamped to [0, 1] before comparing (a renderer that overshoots 1 is judged by what a
//!   display shows). A NaN channel counts as an error of 1 (maximal), never as agreement.
//! - **RMSE** is over the three premultiplied **RGB** channels of every pixel (background
//!   included): what the picture composited over black shows. α is not in the RMSE: over black
//!   it is invisible, and its error follows the colour's.
//! - **PSNR** = 20·log10(peak / RMSE) dB with **peak 1** (the largest clamped channel value),
//!   **capped at [`PSNR_CAP_DB`] = 99 dB** (identical images, RMSE = 0, would be +∞; any RMSE
//!   below 10^(−99/20) ≈ 1.1·10⁻⁵ also reads 99 dB).
//! - The maximum absolute error and the bad-pixel share look at all four channels (RGBA): a
//!   pixel is *covered* when the reference or the rendering has α > 1/255, and *bad* when it is
//!   covered and any channel differs by more than 1/255 (one step of an 8-bit display).

use serde::{Deserialize, Serialize};

use crate::Image;

/// PSNR reported for identical images (RMSE = 0), instead of infinity.
pub const PSNR_CAP_DB: f64 = 99.0;

/// One 8-bit step: the threshold of "covered" and of "bad" pixels.
pub const ONE_STEP: f64 = 1.0 / 255.0;

/// Image error of a rendering against the reference.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ImageError {
    pub rmse: f64,
    pub psnr_db: f64,
    pub max_abs_error: f64,
    /// Share of covered pixels off by more than 1/255 in any channel (0 when none is covered).
    pub bad_pixel_share: f64,
    pub covered_pixels: u64,
    pub bad_pixels: u64,
}

fn clamp01(v: f32) -> f64 {
    if v.is_nan() {
        // A NaN is as wrong as a pixel can be: count it as maximal error, not as agreement.
        return f64::INFINITY;
    }
    (v as f64).clamp(0.0, 1.0)
}

/// Per-channel absolute difference with the NaN convention of [`clamp01`] (NaN → error 1).
pub fn channel_error(a: f32, b: f32) -> f64 {
    let (a, b) = (clamp01(a), clamp01(b));
    if a.is_infinite() || b.is_infinite() {
        1.0
    } else {
        (a - b).abs()
    }
}

/// PSNR in dB for a given RMSE (peak value 1), capped at [`PSNR_CAP_DB`].
pub fn psnr_from_rmse(rmse: f64) -> f64 {
    if rmse <= 0.0 {
        PSNR_CAP_DB
    } else {
        (20.0 * (1.0 / rmse).log10()).min(PSNR_CAP_DB)
    }
}

/// Compares `image` with `reference` (same size required).
pub fn compare(image: &Image, reference: &Image) -> anyhow::Result<ImageError> {
    if image.width != reference.width || image.height != reference.height {
        anyhow::bail!(
            "image is {}x{} but the reference is {}x{}",
            image.width,
            image.height,
            reference.width,
            reference.height
        );
    }
    let mut sum_sq = 0.0f64;
    let mut max_abs = 0.0f64;
    let mut covered = 0u64;
    let mut bad = 0u64;
    for (p, r) in image.pixels.iter().zip(&reference.pixels) {
        let mut pixel_max = 0.0f64;
        for c in 0..4 {
            let e = channel_error(p[c], r[c]);
            if c < 3 {
                sum_sq += e * e;
            }
            pixel_max = pixel_max.max(e);
        }
        max_abs = max_abs.max(pixel_max);
        let is_covered = clamp01(r[3]) > ONE_STEP || clamp01(p[3]) > ONE_STEP;
        if is_covered {
            covered += 1;
            if pixel_max > ONE_STEP {
                bad += 1;
            }
        }
    }
    let n = (image.pixels.len() * 3).max(1) as f64;
    let rmse = (sum_sq / n).sqrt();
    Ok(ImageError {
        rmse,
        psnr_db: psnr_from_rmse(rmse),
        max_abs_error: max_abs,
        bad_pixel_share: if covered > 0 {
            bad as f64 / covered as f64
        } else {
            0.0
        },
        covered_pixels: covered,
        bad_pixels: bad,
    })
}

/// PSNR (dB) of `image` against `reference`, as [`compare`] measures it (RGB, peak 1, capped at
/// [`PSNR_CAP_DB`]). Panics when the sizes differ: for tests, which compare images of one camera.
pub fn psnr(image: &Image, reference: &Image) -> f64 {
    compare(image, reference)
        .unwrap_or_else(|e| panic!("psnr: {e}"))
        .psnr_db
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 4]) -> Image {
        let mut i = Image::new(w, h);
        for y in 0..h {
            for x in 0..w {
                i.set(x, y, f(x, y));
            }
        }
        i
    }

    #[test]
    fn identical_images_have_capped_psnr_and_no_error() {
        let a = img(7, 5, |x, y| [x as f32 / 7.0, y as f32 / 5.0, 0.25, 0.5]);
        let e = compare(&a, &a).unwrap();
        assert_eq!(e.rmse, 0.0);
        assert_eq!(e.psnr_db, PSNR_CAP_DB);
        assert_eq!(e.max_abs_error, 0.0);
        assert_eq!(e.bad_pixel_share, 0.0);
        assert_eq!(e.covered_pixels, 35);
    }

    #[test]
    fn known_rmse_psnr_and_bad_pixels() {
        // 4 pixels; one pixel's red channel off by 0.2: RMSE = sqrt(0.04 / 12).
        let r = img(2, 2, |_, _| [0.5, 0.5, 0.5, 1.0]);
        let mut a = r.clone();
        a.set(1, 0, [0.7, 0.5, 0.5, 1.0]);
        let e = compare(&a, &r).unwrap();
        let want = (0.04f64 / 12.0).sqrt();
        assert!((e.rmse - want).abs() < 1e-7, "{} vs {want}", e.rmse);
        assert!((e.psnr_db - 20.0 * (1.0 / want).log10()).abs() < 1e-5);
        assert!((e.max_abs_error - 0.2).abs() < 1e-6);
        assert_eq!(e.bad_pixels, 1);
        assert!((e.bad_pixel_share - 0.25).abs() < 1e-12);
    }

    #[test]
    fn coverage_counts_either_image_and_ignores_sub_step_errors() {
        // Reference empty; the renderer paints one pixel (covered, bad) and leaves a sub-step
        // haze on another (not covered: α below 1/255).
        let r = img(3, 1, |_, _| [0.0; 4]);
        let mut a = r.clone();
        a.set(0, 0, [0.3, 0.0, 0.0, 0.3]);
        a.set(1, 0, [0.001, 0.0, 0.0, 0.001]);
        let e = compare(&a, &r).unwrap();
        assert_eq!(e.covered_pixels, 1);
        assert_eq!(e.bad_pixels, 1);
        assert_eq!(e.bad_pixel_share, 1.0);
        // Values above 1 are clamped before comparing.
        let hot = img(3, 1, |_, _| [1.5, 1.0, 1.0, 1.0]);
        let one = img(3, 1, |_, _| [1.0, 1.0, 1.0, 1.0]);
        assert_eq!(compare(&hot, &one).unwrap().rmse, 0.0);
    }

    #[test]
    fn nan_pixels_count_as_wrong_and_sizes_must_match() {
        let r = img(2, 1, |_, _| [0.5, 0.5, 0.5, 1.0]);
        let mut a = r.clone();
        a.set(0, 0, [f32::NAN, 0.5, 0.5, 1.0]);
        let e = compare(&a, &r).unwrap();
        assert_eq!(e.max_abs_error, 1.0);
        assert!(e.psnr_db.is_finite() && e.psnr_db < 10.0);
        assert!(compare(&img(2, 2, |_, _| [0.0; 4]), &r).is_err());
    }

    #[test]
    fn psnr_is_compare_s_psnr() {
        let r = img(2, 2, |_, _| [0.5, 0.5, 0.5, 1.0]);
        let mut a = r.clone();
        a.set(0, 1, [0.5, 0.4, 0.5, 1.0]);
        assert_eq!(psnr(&a, &r), compare(&a, &r).unwrap().psnr_db);
        // α alone is not in the RMSE (invisible over black).
        let mut alpha = r.clone();
        alpha.set(0, 0, [0.5, 0.5, 0.5, 0.2]);
        assert_eq!(psnr(&alpha, &r), PSNR_CAP_DB);
    }
}
