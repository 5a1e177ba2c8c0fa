//! Images as every renderer returns them: premultiplied RGBA, linear, f32, row 0 at the top.

use std::path::Path;

/// A premultiplied, linear-light RGBA image. Row 0 is the top of the screen.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Image {
        Image {
            width,
            height,
            pixels: vec![[0.0; 4]; (width * height) as usize],
        }
    }
    pub fn get(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[(y * self.width + x) as usize]
    }
    pub fn set(&mut self, x: u32, y: u32, v: [f32; 4]) {
        self.pixels[(y * self.width + x) as usize] = v;
    }

    /// 8-bit sRGB of the premultiplied image composited over black (the papers' background).
    pub fn to_srgb8(&self) -> image::RgbaImage {
        let mut out = image::RgbaImage::new(self.width, self.height);
        for (i, p) in self.pixels.iter().enumerate() {
            let x = i as u32 % self.width;
            let y = i as u32 / self.width;
            let c =
                [p[0], p[1], p[2]].map(|v| (linear_to_srgb(v.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8);
            out.put_pixel(x, y, image::Rgba([c[0], c[1], c[2], 255]));
        }
        out
    }

    pub fn save_png(&self, path: &Path) -> anyhow::Result<()> {
        self.to_srgb8()
            .save(path)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))
    }
}

/// The sRGB transfer function (IEC 61966-2-1).
pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}
