//! compare's image verdict: rendering is deterministic on one adapter, so any changed f32
//! pixel is reported (hash of the pixels; with both images present the changed-pixel count,
//! largest difference and a heatmap), as is any PSNR change > 0.1 dB; a PSNR drop > 0.1 dB is
//! a regression.

use std::path::Path;

use anyhow::Context;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::regress::compare_setup::CompareOptions;
use crate::results::samples;
use crate::results::Row;

/// A PSNR change larger than this is reported (and a drop this large is a regression).
pub const PSNR_TOLERANCE_DB: f64 = 0.1;

/// What became of a row's image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum ImageVerdict {
    /// Bit-identical pixels (or no pixels to compare) and PSNR within the tolerance.
    Same,
    /// Pixels differ, PSNR within the tolerance.
    Changed,
    /// PSNR up by more than the tolerance.
    Better,
    /// PSNR down by more than the tolerance: a regression.
    Worse,
}

impl ImageVerdict {
    pub fn label(self) -> &'static str {
        match self {
            ImageVerdict::Same => "same",
            ImageVerdict::Changed => "changed",
            ImageVerdict::Better => "better",
            ImageVerdict::Worse => "worse",
        }
    }
}

impl std::fmt::Display for ImageVerdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ImageChange {
    pub psnr_base_db: Option<f64>,
    pub psnr_new_db: Option<f64>,
    pub psnr_delta_db: Option<f64>,
    /// Whether the pixels' hashes differ (`None`: a side has no hash, or --normalised).
    pub pixels_changed: Option<bool>,
    /// With both f32 images at hand: pixels with any channel changed, largest difference, and
    /// the heatmap of the difference (relative to the compare output directory).
    pub changed_pixels: Option<u64>,
    pub max_abs_difference: Option<f64>,
    pub heatmap: String,
    pub verdict: ImageVerdict,
}

pub(crate) fn image_note(i: &ImageChange) -> String {
    let mut s = format!("image {}", i.verdict);
    if let Some(d) = i.psnr_delta_db {
        s.push_str(&format!(" (PSNR {d:+.2} dB"));
        if let Some(c) = i.changed_pixels {
            s.push_str(&format!(", {c} pixels differ"));
        }
        s.push(')');
    } else if let Some(c) = i.changed_pixels {
        s.push_str(&format!(" ({c} pixels differ)"));
    }
    s
}

pub(crate) fn image_change(
    b: &Row,
    n: &Row,
    base_dir: &Path,
    new_dir: &Path,
    heat_dir: &Path,
    opt: &CompareOptions,
) -> anyhow::Result<ImageChange> {
    let delta = b.psnr_db.zip(n.psnr_db).map(|(b, n)| n - b);
    let mut c = ImageChange {
        psnr_base_db: b.psnr_db,
        psnr_new_db: n.psnr_db,
        psnr_delta_db: delta,
        pixels_changed: None,
        changed_pixels: None,
        max_abs_difference: None,
        heatmap: String::new(),
        verdict: ImageVerdict::Same,
    };
    if !opt.normalised {
        if !b.image_hash.is_empty() && !n.image_hash.is_empty() {
            c.pixels_changed = Some(b.image_hash != n.image_hash);
        }
        if let (Some(bp), Some(np)) = (
            samples::row_image(base_dir, b),
            samples::row_image(new_dir, n),
        ) {
            let (bi, ni) = (samples::read_f32_image(&bp)?, samples::read_f32_image(&np)?);
            let d = image_difference(&bi, &ni)?;
            c.changed_pixels = Some(d.changed_pixels);
            c.max_abs_difference = Some(d.max_abs);
            c.pixels_changed = Some(d.changed_pixels > 0);
            if d.changed_pixels > 0 {
                std::fs::create_dir_all(heat_dir)
                    .with_context(|| format!("cannot create {}", heat_dir.display()))?;
                let name = format!(
                    "{}__{}__{}__{}.png",
                    crate::results::names::slug(&b.dataset),
                    crate::results::names::viewpoint_slug(&b.viewpoint),
                    crate::results::names::slug(&b.algorithm),
                    crate::results::names::slug(&b.settings.to_string())
                );
                let path = heat_dir.join(&name);
                d.heatmap
                    .save(&path)
                    .with_context(|| format!("cannot write {}", path.display()))?;
                c.heatmap = format!("heatmaps/{name}");
            }
        }
    }
    c.verdict = match delta {
        Some(d) if d < -PSNR_TOLERANCE_DB => ImageVerdict::Worse,
        Some(d) if d > PSNR_TOLERANCE_DB => ImageVerdict::Better,
        _ if c.pixels_changed == Some(true) => ImageVerdict::Changed,
        _ => ImageVerdict::Same,
    };
    Ok(c)
}

/// Where two renderings of the same row differ.
pub struct ImageDifference {
    /// Pixels with any channel not bit-identical.
    pub changed_pixels: u64,
    pub max_abs: f64,
    /// Black where identical; changed pixels on a log ramp from 1e-7 (a last-bit change still
    /// shows) to 0.25 and above.
    pub heatmap: image::RgbImage,
}

pub fn image_difference(
    base: &render_core::Image,
    new: &render_core::Image,
) -> anyhow::Result<ImageDifference> {
    if (base.width, base.height) != (new.width, new.height) {
        anyhow::bail!(
            "images differ in size: {}x{} vs {}x{}",
            base.width,
            base.height,
            new.width,
            new.height
        );
    }
    let mut heat = image::RgbImage::new(base.width, base.height);
    let (mut changed, mut max_abs) = (0u64, 0.0f64);
    let (lo, hi) = (1e-7f64.ln(), 0.25f64.ln());
    for (i, (a, b)) in base.pixels.iter().zip(&new.pixels).enumerate() {
        if a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()) {
            continue;
        }
        changed += 1;
        let d = a
            .iter()
            .zip(b)
            .map(|(x, y)| {
                let d = (*x as f64 - *y as f64).abs();
                if d.is_nan() {
                    1.0
                } else {
                    d
                }
            })
            .fold(0.0, f64::max);
        max_abs = max_abs.max(d);
        let t = ((d.max(1e-7).ln() - lo) / (hi - lo)).clamp(0.0, 1.0);
        heat.put_pixel(
            i as u32 % base.width,
            i as u32 / base.width,
            image::Rgb(crate::results::metrics::ramp(t)),
        );
    }
    Ok(ImageDifference {
        changed_pixels: changed,
        max_abs,
        heatmap: heat,
    })
}
