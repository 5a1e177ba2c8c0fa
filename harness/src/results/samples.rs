//! What a row keeps besides its medians, so that two runs can be compared properly: the
//! per-frame samples (total, CPU and GPU ms of every timed frame) and the exact f32 image.
//!
//! - Samples live in each row of `results.json` (`samples`) and, one line per frame and
//!   metric, in `samples.csv` (long format: easy to load into pandas, R or a spreadsheet).
//! - The image is stored as `…​.f32.zz`: a small header and the zlib-compressed RGBA f32
//!   pixels with their bytes split into four planes (all first bytes, then all second bytes, …),
//!   which compresses floats far better than interleaved bytes. flate2 is already a dependency
//!   (an EXR writer would add a crate for no gain: we only need a lossless round trip). The
//!   row also carries the blake3 hash of the raw pixels (`image_hash`), so a results set
//!   without the image files (a committed baseline) still tells exactly whether an image changed.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use anyhow::anyhow;
use render_core::Image;

use crate::results::{read_bytes, write_file, Row};

pub use crate::results::{
    sample_lines, write_samples_csv, FrameSamples, SampleLine, SamplesWriter, SAMPLES_CSV,
};

// ---------------------------------------------------------------------------------------------
// Exact f32 images
// ---------------------------------------------------------------------------------------------

const IMAGE_MAGIC: &[u8; 8] = b"TBF32\x00\x00\x01";
pub const IMAGE_EXTENSION: &str = "f32.zz";

fn raw_bytes(img: &Image) -> Vec<u8> {
    let mut raw = Vec::with_capacity(img.pixels.len() * 16);
    for p in &img.pixels {
        for c in p {
            raw.extend_from_slice(&c.to_le_bytes());
        }
    }
    raw
}

/// blake3 of the little-endian f32 RGBA pixels and the size, hex (what `image_hash` holds).
pub fn image_hash(img: &Image) -> String {
    let mut h = blake3::Hasher::new();
    h.update(&img.width.to_le_bytes());
    h.update(&img.height.to_le_bytes());
    h.update(&raw_bytes(img));
    h.finalize().to_hex().to_string()
}

/// Writes `img` losslessly to `path`; returns the compressed size in bytes.
pub fn write_f32_image(path: &Path, img: &Image) -> anyhow::Result<u64> {
    let raw = raw_bytes(img);
    // Byte planes: byte k of every float together (exponents and high mantissa bytes repeat).
    let mut planes = Vec::with_capacity(raw.len());
    for k in 0..4 {
        planes.extend(raw.iter().skip(k).step_by(4));
    }
    let mut bytes = Vec::with_capacity(raw.len() / 4 + 16);
    bytes.extend_from_slice(IMAGE_MAGIC);
    bytes.extend_from_slice(&img.width.to_le_bytes());
    bytes.extend_from_slice(&img.height.to_le_bytes());
    let mut enc = flate2::write::ZlibEncoder::new(bytes, flate2::Compression::default());
    enc.write_all(&planes)?;
    let bytes = enc.finish()?;
    write_file(path, &bytes)?;
    Ok(bytes.len() as u64)
}

/// Reads an image written by [`write_f32_image`]; a damaged file is an error naming it.
pub fn read_f32_image(path: &Path) -> anyhow::Result<Image> {
    let bytes = read_bytes(path)?;
    let bad = |what: &str| anyhow!("{}: not a tetbench f32 image ({what})", path.display());
    if bytes.len() < 16 || &bytes[..8] != IMAGE_MAGIC {
        return Err(bad("wrong magic"));
    }
    let w = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    let h = u32::from_le_bytes(bytes[12..16].try_into().expect("4 bytes"));
    let n = (w as usize)
        .checked_mul(h as usize)
        .and_then(|p| p.checked_mul(16))
        .filter(|&n| n <= 1 << 32)
        .ok_or_else(|| bad("size out of range"))?;
    let mut planes = Vec::with_capacity(n);
    flate2::read::ZlibDecoder::new(&bytes[16..])
        .take(n as u64 + 1)
        .read_to_end(&mut planes)
        .map_err(|e| bad(&format!("corrupt data: {e}")))?;
    if planes.len() != n {
        return Err(bad(&format!(
            "{} bytes of pixels, expected {n}",
            planes.len()
        )));
    }
    let q = n / 4;
    let mut img = Image::new(w, h);
    for (i, px) in img.pixels.iter_mut().enumerate() {
        for (c, v) in px.iter_mut().enumerate() {
            let j = i * 4 + c;
            *v = f32::from_le_bytes([
                planes[j],
                planes[q + j],
                planes[2 * q + j],
                planes[3 * q + j],
            ]);
        }
    }
    Ok(img)
}

/// The f32 image of a row, if the row names one and it exists under `dir`.
pub fn row_image(dir: &Path, row: &Row) -> Option<PathBuf> {
    (!row.image_f32.is_empty())
        .then(|| dir.join(&row.image_f32))
        .filter(|p| p.is_file())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f32_images_round_trip_bit_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = Image::new(7, 5);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = [i as f32 * 0.013, -0.0, f32::NAN, 1e-30 * i as f32];
        }
        let path = dir.path().join(format!("a.{IMAGE_EXTENSION}"));
        write_f32_image(&path, &img).unwrap();
        let back = read_f32_image(&path).unwrap();
        let bits =
            |i: &Image| -> Vec<u32> { i.pixels.iter().flatten().map(|v| v.to_bits()).collect() };
        assert_eq!((back.width, back.height), (7, 5));
        assert_eq!(bits(&back), bits(&img));
        assert_eq!(image_hash(&back), image_hash(&img));
        std::fs::write(&path, b"TBF32\x00\x00\x01garbage!").unwrap();
        let e = read_f32_image(&path).unwrap_err().to_string();
        assert!(e.contains("a.f32.zz"), "{e}");
    }

    #[test]
    fn one_changed_value_changes_the_hash() {
        let a = Image::new(4, 4);
        let mut b = a.clone();
        b.pixels[5][1] = f32::from_bits(1);
        assert_ne!(image_hash(&a), image_hash(&b));
    }
}
