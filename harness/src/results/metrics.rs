//! Timing summaries and image error against the exact reference.
//!
//! The image error itself (RMSE, PSNR, bad pixels; what each measures) is
//! [`render_core::image_error`], re-exported here: the renderers' own tests use the same
//! implementation without depending on the harness.

use render_core::Image;

pub use render_core::image_error::{
    channel_error, compare, psnr, psnr_from_rmse, ImageError, ONE_STEP, PSNR_CAP_DB,
};
use serde::{Deserialize, Serialize};

/// Median, minimum and maximum of a series (ms).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

/// Median (mean of the two middle values for an even count), min and max; `None` when empty.
pub fn summarize(values: &[f64]) -> Option<Summary> {
    if values.is_empty() {
        return None;
    }
    let mut v = values.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    let median = if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    };
    Some(Summary {
        median,
        min: v[0],
        max: v[n - 1],
    })
}

/// Largest error shown at full brightness in heatmaps; errors at or below one 8-bit step are
/// black. The scale between is logarithmic, so both "a few steps off" and "badly wrong" read.
pub const HEATMAP_MAX_ERROR: f64 = 0.25;

/// The error heatmap: per pixel the largest channel error (RGBA), black at ≤ 1/255, through
/// blue, magenta and orange to yellow-white at ≥ [`HEATMAP_MAX_ERROR`] (log scale). Pixels
/// covered by neither image stay black.
pub fn heatmap(image: &Image, reference: &Image) -> anyhow::Result<image::RgbImage> {
    if image.width != reference.width || image.height != reference.height {
        anyhow::bail!("heatmap: image and reference sizes differ");
    }
    let mut out = image::RgbImage::new(image.width, image.height);
    let lo = ONE_STEP.ln();
    let hi = HEATMAP_MAX_ERROR.ln();
    for (i, (p, r)) in image.pixels.iter().zip(&reference.pixels).enumerate() {
        let e = (0..4)
            .map(|c| channel_error(p[c], r[c]))
            .fold(0.0, f64::max);
        let rgb = if e <= ONE_STEP {
            [0, 0, 0]
        } else {
            ramp(((e.ln() - lo) / (hi - lo)).clamp(0.0, 1.0))
        };
        out.put_pixel(
            i as u32 % image.width,
            i as u32 / image.width,
            image::Rgb(rgb),
        );
    }
    Ok(out)
}

/// A perceptually ordered ramp (dark blue → magenta → orange → pale yellow), in the spirit of
/// matplotlib's "inferno", for t ∈ [0, 1]. Starts visibly above black so 2/255 errors show.
pub fn ramp(t: f64) -> [u8; 3] {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.0, [40.0, 20.0, 110.0]),
        (0.3, [120.0, 30.0, 150.0]),
        (0.55, [210.0, 60.0, 80.0]),
        (0.8, [250.0, 150.0, 30.0]),
        (1.0, [255.0, 255.0, 190.0]),
    ];
    let t = t.clamp(0.0, 1.0);
    let i = STOPS
        .iter()
        .position(|s| s.0 >= t)
        .unwrap_or(STOPS.len() - 1)
        .max(1);
    let (a, b) = (STOPS[i - 1], STOPS[i]);
    let u = (t - a.0) / (b.0 - a.0);
    [0, 1, 2].map(|k| (a.1[k] + u * (b.1[k] - a.1[k])).round() as u8)
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
    fn summary_median_min_max() {
        assert_eq!(summarize(&[]), None);
        let s = summarize(&[5.0, 1.0, 3.0]).unwrap();
        assert_eq!((s.median, s.min, s.max), (3.0, 1.0, 5.0));
        let s = summarize(&[4.0, 1.0, 3.0, 2.0]).unwrap();
        assert_eq!((s.median, s.min, s.max), (2.5, 1.0, 4.0));
    }

    #[test]
    fn heatmap_is_black_where_images_agree_within_a_step() {
        let r = img(3, 1, |_, _| [0.5, 0.5, 0.5, 1.0]);
        let mut a = r.clone();
        a.set(1, 0, [0.5 + 0.5 / 255.0, 0.5, 0.5, 1.0]);
        a.set(2, 0, [1.0, 0.5, 0.5, 1.0]);
        let h = heatmap(&a, &r).unwrap();
        assert_eq!(h.get_pixel(0, 0).0, [0, 0, 0]);
        assert_eq!(h.get_pixel(1, 0).0, [0, 0, 0]);
        assert_eq!(h.get_pixel(2, 0).0, ramp(1.0));
        assert_ne!(ramp(0.0), [0, 0, 0]);
    }
}
