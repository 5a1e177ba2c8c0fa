//! Small helpers every reader shares: file reads and error locations, bulk byte conversions
//! and the byte-order plausibility test, regular-grid points and checked grid sizes.

use std::path::Path;

use crate::error::{ErrorKind, LoadError, Location};

pub(crate) fn trim_start(b: &[u8]) -> &[u8] {
    let n = b.iter().take_while(|c| c.is_ascii_whitespace()).count();
    &b[n..]
}

pub(crate) fn io_error(path: &Path, e: &std::io::Error) -> LoadError {
    LoadError::new(path, ErrorKind::Io(e.to_string()))
}

/// Reads a whole file, mapping failures to a [`LoadError`] naming it.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, LoadError> {
    std::fs::read(path).map_err(|e| io_error(path, &e))
}

/// The mesh name used in reports: the file stem.
pub(crate) fn stem_name(path: &Path) -> String {
    path.file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("mesh")
        .to_string()
}

/// 1-based line of byte offset `pos` in a text file (computed only when reporting an error).
pub(crate) fn line_of(bytes: &[u8], pos: usize) -> Location {
    let end = pos.min(bytes.len());
    Location::Line(1 + bytes[..end].iter().filter(|&&c| c == b'\n').count())
}

// ---------------------------------------------------------------------------------------------
// Bulk byte conversions. One pass over `chunks_exact`, no per-value allocation: this is what
// keeps loading Blunt Fin far below the 0.2 s goal.

/// Byte order of binary data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ByteOrder {
    Big,
    Little,
}

macro_rules! bulk {
    ($name:ident, $t:ty, $n:expr) => {
        /// Converts packed values of this type in the given byte order.
        pub(crate) fn $name(bytes: &[u8], order: ByteOrder) -> Vec<$t> {
            let it = bytes.chunks_exact($n).map(|c| {
                let a: [u8; $n] = c.try_into().unwrap_or([0; $n]);
                a
            });
            match order {
                ByteOrder::Big => it.map(<$t>::from_be_bytes).collect(),
                ByteOrder::Little => it.map(<$t>::from_le_bytes).collect(),
            }
        }
    };
}
bulk!(f32s, f32, 4);
bulk!(f64s, f64, 8);
bulk!(i32s, i32, 4);

/// Whether the non-finite values of a block read in its declared byte order are better explained
/// by a byte-order mix-up: read the other way the block has no non-finite value and fewer
/// implausible magnitudes (non-zero below 1e-30 or above 1e30: what reversed bytes of ordinary
/// floats give). A lone NaN in otherwise sane data stays a NaN.
pub(crate) fn looks_byte_swapped(declared: &[f32], swapped: &[f32]) -> bool {
    let implausible =
        |v: &&f32| !v.is_finite() || (**v != 0.0 && (v.abs() < 1e-30 || v.abs() > 1e30));
    swapped.iter().all(|v| v.is_finite())
        && swapped.iter().filter(implausible).count() < declared.iter().filter(implausible).count()
}

/// Magnitude of each tuple of an `ncomp`-component array (the scalar used for vector arrays).
pub(crate) fn tuple_magnitudes(values: &[f32], ncomp: usize) -> Vec<f32> {
    if ncomp <= 1 {
        return values.to_vec();
    }
    values
        .chunks_exact(ncomp)
        .map(|t| {
            t.iter()
                .map(|&x| (x as f64) * (x as f64))
                .sum::<f64>()
                .sqrt() as f32
        })
        .collect()
}

/// Regular grid points: origin + index · spacing, x fastest.
pub(crate) fn grid_points(dims: [usize; 3], origin: [f64; 3], spacing: [f64; 3]) -> Vec<[f32; 3]> {
    let mut pts = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                pts.push([
                    (origin[0] + i as f64 * spacing[0]) as f32,
                    (origin[1] + j as f64 * spacing[1]) as f32,
                    (origin[2] + k as f64 * spacing[2]) as f32,
                ]);
            }
        }
    }
    pts
}

/// Checked point count of a grid: `IndexOverflow` beyond 32-bit indices.
pub(crate) fn grid_count(dims: [u64; 3]) -> Result<usize, ErrorKind> {
    let n = dims[0]
        .checked_mul(dims[1])
        .and_then(|x| x.checked_mul(dims[2]));
    match n {
        Some(n) if n <= u32::MAX as u64 => Ok(n as usize),
        _ => Err(ErrorKind::IndexOverflow {
            what: format!("grid points ({}×{}×{})", dims[0], dims[1], dims[2]),
            count: n.unwrap_or(u64::MAX),
        }),
    }
}
