//! PLOT3D whole-grid 3-D binary files: an XYZ grid file plus a Q (solution) file, the format of
//! the NASA data sets the papers render (Blunt Fin, Combustion Chamber, LOx Post).
//!
//! Nothing in the files says how they were written, so the layout is sniffed from the header
//! and the file size: byte order (big or little), Fortran record markers or none, single-grid
//! (`ni nj nk`) or multi-grid with one block (`1`, then `ni nj nk`), f32 or f64, and for XYZ
//! with or without an IBLANK block. A layout is accepted when its size formula gives exactly the
//! file size, or a smaller size followed only by zero bytes (the Blunt Fin Q file has 484 bytes
//! of padding). The grid becomes tets with [`structured_tets`] (5 per hexahedral cell,
//! alternating parity): Blunt Fin 40×32×32 gives the papers' 187,395 tets.
//!
//! The Q file holds ρ, ρu, ρv, ρw, E per point; [`Plot3dField`] picks the scalar, pressure with
//! γ = 1.4. Blanked points (IBLANK = 0) are kept — the papers render every cell — and reported
//! in `repair.warnings`.

use std::path::{Path, PathBuf};

use crate::dataset::{Dataset, LoadOptions, Plot3dField};
use crate::error::{ErrorKind, LoadError, Location};
use crate::read_util::{self as util, ByteOrder};
use crate::volume::structured_tets;
use crate::TetMesh;

/// Ratio of specific heats used for pressure.
pub const GAMMA: f64 = 1.4;

/// Reads an XYZ grid file and its Q file (`options.q_file`, else [`q_path_for`]).
pub fn read(path: &Path, options: &LoadOptions) -> Result<Dataset, LoadError> {
    let xyz = util::read_file(path)?;
    let q_path = match &options.q_file {
        Some(q) => q.clone(),
        None => q_path_for(path).ok_or_else(|| {
            LoadError::new(path, ErrorKind::Invalid("cannot derive the Q file name (no \"xyz\" or \".x\" in the name): give it explicitly".into()))
        })?,
    };
    let q = std::fs::read(&q_path).map_err(|e| {
        LoadError::new(
            &q_path,
            ErrorKind::Io(format!(
                "the PLOT3D Q file for {}: {e} (name it explicitly if it lives elsewhere)",
                path.display()
            )),
        )
    })?;
    from_bytes(&xyz, &q, path, &q_path, options)
}

/// The Q file beside an XYZ file by the usual naming: the last `xyz` of the file name becomes
/// `q` (`bluntfinxyz.bin` → `bluntfinq.bin`, `post.xyz` → `post.q`), or extension `.x` → `.q`.
pub fn q_path_for(xyz: &Path) -> Option<PathBuf> {
    let name = xyz.file_name()?.to_str()?;
    let lower = name.to_ascii_lowercase();
    if let Some(i) = lower.rfind("xyz") {
        let q = if &name[i..i + 3] == "XYZ" { "Q" } else { "q" };
        return Some(xyz.with_file_name(format!("{}{}{}", &name[..i], q, &name[i + 3..])));
    }
    match xyz.extension()?.to_str()? {
        "x" => Some(xyz.with_extension("q")),
        "X" => Some(xyz.with_extension("Q")),
        _ => None,
    }
}

/// The data set name: the XYZ file stem without its `xyz`.
fn grid_name(path: &Path) -> String {
    let stem = util::stem_name(path);
    let lower = stem.to_ascii_lowercase();
    match lower.rfind("xyz") {
        Some(i) if stem.len() > 3 => format!("{}{}", &stem[..i], &stem[i + 3..]),
        _ => stem,
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FileKind {
    Xyz,
    Q,
}

/// One way of reading a file, found by [`sniff`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Layout {
    order: ByteOrder,
    markers: bool,
    multi: bool,
    /// Bytes per real: 4 or 8.
    prec: usize,
    iblank: bool,
    dims: [usize; 3],
    /// Offset of the first value after the header (past its record marker, if any).
    data_at: usize,
    /// Trailing zero bytes after the data.
    padding: usize,
}

impl Layout {
    fn points(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }
    fn describe(&self) -> String {
        format!(
            "{}×{}×{} grid, {}-endian f{}{}{}{}",
            self.dims[0],
            self.dims[1],
            self.dims[2],
            if self.order == ByteOrder::Big {
                "big"
            } else {
                "little"
            },
            self.prec * 8,
            if self.iblank { ", IBLANK" } else { "" },
            if self.markers {
                ", Fortran record markers"
            } else {
                ""
            },
            if self.multi {
                ", multi-grid header"
            } else {
                ""
            }
        )
    }
}

fn rd_i32(b: &[u8], at: usize, order: ByteOrder) -> Option<i64> {
    let c: [u8; 4] = b.get(at..at.checked_add(4)?)?.try_into().ok()?;
    Some(match order {
        ByteOrder::Big => i32::from_be_bytes(c),
        ByteOrder::Little => i32::from_le_bytes(c),
    } as i64)
}

/// Header of one (byte order, markers, multi-grid) guess: grid dims and where the data record
/// starts (at its leading marker when there are markers).
fn header(b: &[u8], order: ByteOrder, markers: bool, multi: bool) -> Option<([i64; 3], usize)> {
    let rd = |at| rd_i32(b, at, order);
    let mut at = 0;
    if multi {
        if markers {
            if rd(0)? != 4 || rd(4)? != 1 || rd(8)? != 4 {
                return None;
            }
            at = 12;
        } else {
            if rd(0)? != 1 {
                return None;
            }
            at = 4;
        }
    }
    if markers {
        if rd(at)? != 12 {
            return None;
        }
        at += 4;
    }
    let d = [rd(at)?, rd(at + 4)?, rd(at + 8)?];
    at += 12;
    if markers {
        if rd(at)? != 12 {
            return None;
        }
        at += 4;
    }
    Some((d, at))
}

/// Size in bytes of the records after the header (markers included).
fn body_size(kind: FileKind, n: u64, prec: u64, iblank: bool, markers: bool) -> Option<u64> {
    let m = if markers { 8 } else { 0 };
    match kind {
        FileKind::Xyz => Some(3 * n * prec + if iblank { 4 * n } else { 0 } + m),
        // Four reals (mach, alpha, Re, time), then ρ, ρu, ρv, ρw, E.
        FileKind::Q => Some(4 * prec + m + 5 * n * prec + m),
    }
}

/// Checks the record markers around the data of a guess (they must hold the record lengths).
fn markers_ok(b: &[u8], kind: FileKind, l: &Layout) -> bool {
    if !l.markers {
        return true;
    }
    let n = l.points() as u64;
    let p = l.prec as u64;
    let rec_ok = |at: usize, len: u64| -> bool {
        rd_i32(b, at, l.order).map(|v| v as u32 as u64) == Some(len)
            && rd_i32(b, at + 4 + len as usize, l.order).map(|v| v as u32 as u64) == Some(len)
    };
    match kind {
        FileKind::Xyz => rec_ok(l.data_at - 4, 3 * n * p + if l.iblank { 4 * n } else { 0 }),
        FileKind::Q => {
            rec_ok(l.data_at - 4, 4 * p) && rec_ok(l.data_at + 4 * p as usize + 4, 5 * n * p)
        }
    }
}

/// What went wrong when no layout explains the file.
struct SniffError {
    at: u64,
    kind: ErrorKind,
}

/// Finds the layout of an XYZ or Q file (see the module doc). `b` may be only the head of the
/// file (then `len` is the full size and padding is not checked).
fn sniff(b: &[u8], len: u64, kind: FileKind) -> Result<Layout, SniffError> {
    let mut exact: Option<Layout> = None;
    let mut padded: Option<Layout> = None;
    let mut plausible: Option<(Layout, u64)> = None;
    let mut overflow: Option<[i64; 3]> = None;
    let orders = [ByteOrder::Big, ByteOrder::Little];
    for markers in [false, true] {
        for multi in [false, true] {
            for order in orders {
                let Some((d, data_at)) = header(b, order, markers, multi) else {
                    continue;
                };
                if d.iter().any(|&x| x < 1) {
                    continue;
                }
                let n = match util::grid_count(d.map(|x| x as u64)) {
                    Ok(n) => n as u64,
                    Err(_) => {
                        overflow.get_or_insert(d);
                        continue;
                    }
                };
                let head = data_at as u64;
                for prec in [4u64, 8] {
                    for iblank in [false, true] {
                        if iblank && kind == FileKind::Q {
                            continue;
                        }
                        let Some(expected) =
                            body_size(kind, n, prec, iblank, markers).map(|s| s + head)
                        else {
                            continue;
                        };
                        let l = Layout {
                            order,
                            markers,
                            multi,
                            prec: prec as usize,
                            iblank,
                            dims: d.map(|x| x as usize),
                            data_at: data_at + if markers { 4 } else { 0 },
                            padding: len.saturating_sub(expected) as usize,
                        };
                        if plausible.is_none() {
                            plausible = Some((l, expected));
                        }
                        let full = b.len() as u64 == len;
                        if expected == len {
                            if exact.is_none() && (!full || markers_ok(b, kind, &l)) {
                                exact = Some(l);
                            }
                        } else if expected < len
                            && full
                            && b[expected as usize..].iter().all(|&c| c == 0)
                            && markers_ok(b, kind, &l)
                            && padded.is_none_or(|p| p.padding > l.padding)
                        {
                            padded = Some(l);
                        }
                    }
                }
            }
        }
    }
    if let Some(l) = exact.or(padded) {
        return Ok(l);
    }
    let what = if kind == FileKind::Xyz {
        "XYZ grid"
    } else {
        "Q solution"
    };
    if let Some((l, expected)) = plausible {
        let desc = l.describe();
        return Err(if len < expected {
            SniffError {
                at: len,
                kind: ErrorKind::Truncated {
                    expected: format!(
                        "{expected} bytes for a PLOT3D {what} file ({desc}), the file has {len}"
                    ),
                },
            }
        } else {
            SniffError {
                at: expected,
                kind: ErrorKind::CountMismatch {
                    what: format!("size in bytes of a PLOT3D {what} file ({desc}; no other layout fits either)"),
                    expected,
                    found: len,
                },
            }
        });
    }
    if let Some(d) = overflow {
        return Err(SniffError {
            at: 0,
            kind: ErrorKind::IndexOverflow {
                what: format!("grid points ({}×{}×{})", d[0], d[1], d[2]),
                count: d
                    .iter()
                    .map(|&x| x as u64)
                    .fold(1u64, |a, x| a.saturating_mul(x)),
            },
        });
    }
    if len < 12 {
        return Err(SniffError {
            at: len,
            kind: ErrorKind::Truncated {
                expected: "a 12-byte PLOT3D header (ni nj nk)".into(),
            },
        });
    }
    Err(SniffError {
        at: 0,
        kind: ErrorKind::Syntax {
            expected: "a PLOT3D header: ni nj nk as positive 32-bit ints in either byte order, optionally in Fortran records".into(),
            found: format!("{:02x?}", &b[..b.len().min(16)]),
        },
    })
}

/// Whether the head of a file looks like a PLOT3D XYZ file of exactly `len` bytes.
pub(crate) fn sniff_xyz_header(head: &[u8], len: u64) -> bool {
    sniff(head, len, FileKind::Xyz).is_ok()
}

/// Reals of one block in the layout's precision and order, as f32.
fn block(b: &[u8], l: &Layout, at: usize, n: usize) -> Vec<f32> {
    let raw = &b[at..at + n * l.prec];
    if l.prec == 4 {
        util::f32s(raw, l.order)
    } else {
        util::f64s(raw, l.order)
            .into_iter()
            .map(|v| v as f32)
            .collect()
    }
}

/// First non-finite value of a block, as an error: `ByteOrder` when the same bytes read in
/// the other byte order look like sane data (header and data disagree), else `NonFinite`.
fn check_finite(
    b: &[u8],
    l: &Layout,
    at: usize,
    values: &[f32],
    what: &str,
    path: &Path,
) -> Result<(), LoadError> {
    let Some(i) = values.iter().position(|v| !v.is_finite()) else {
        return Ok(());
    };
    let other = Layout {
        order: if l.order == ByteOrder::Big {
            ByteOrder::Little
        } else {
            ByteOrder::Big
        },
        ..*l
    };
    if util::looks_byte_swapped(values, &block(b, &other, at, values.len())) {
        return Err(LoadError::at(
            path,
            Location::Byte((at + i * l.prec) as u64),
            ErrorKind::ByteOrder(format!(
                "{what} {i} is {} read {:?}-endian as the header says, but the data reads as sane values in the other byte order",
                values[i], l.order
            )),
        ));
    }
    Err(LoadError::at(
        path,
        Location::Byte((at + i * l.prec) as u64),
        ErrorKind::NonFinite {
            what: what.into(),
            index: i as u64,
            value: values[i] as f64,
        },
    ))
}

/// The grid's points: the three coordinate blocks of the XYZ file, each checked finite.
fn grid_points(xyz: &[u8], gl: &Layout, xyz_path: &Path) -> Result<Vec<[f32; 3]>, LoadError> {
    let n = gl.points();
    let mut coords = Vec::with_capacity(3);
    for a in 0..3 {
        let at = gl.data_at + a * n * gl.prec;
        let c = block(xyz, gl, at, n);
        check_finite(
            xyz,
            gl,
            at,
            &c,
            &format!("{} coordinate of point", ["x", "y", "z"][a]),
            xyz_path,
        )?;
        coords.push(c);
    }
    Ok((0..n)
        .map(|i| [coords[0][i], coords[1][i], coords[2][i]])
        .collect())
}

/// The Q field the options ask for (`--scalar` by name, else the PLOT3D field option).
fn requested_field(options: &LoadOptions, q_path: &Path) -> Result<Plot3dField, LoadError> {
    Ok(match &options.scalar {
        Some(name) => Plot3dField::from_name(name).ok_or_else(|| {
            LoadError::new(
                q_path,
                ErrorKind::MissingArray {
                    name: name.clone(),
                    available: Plot3dField::ALL
                        .iter()
                        .map(|f| f.name().to_string())
                        .collect(),
                },
            )
        })?,
        None => options.plot3d_field.unwrap_or_default(),
    })
}

/// Parses an XYZ file and its Q file from memory; the paths only name them in errors. Never
/// panics on any input (fuzzed: `datasets/fuzz`).
pub fn from_bytes(
    xyz: &[u8],
    q: &[u8],
    xyz_path: &Path,
    q_path: &Path,
    options: &LoadOptions,
) -> Result<Dataset, LoadError> {
    let gl = sniff(xyz, xyz.len() as u64, FileKind::Xyz).map_err(|e| {
        // A Q file given as the grid: say so rather than complain about its size.
        let kind = if sniff(xyz, xyz.len() as u64, FileKind::Q).is_ok() {
            ErrorKind::Invalid(
                "this is a PLOT3D Q (solution) file; load the XYZ grid file beside it".into(),
            )
        } else {
            e.kind
        };
        LoadError::at(xyz_path, Location::Byte(e.at), kind)
    })?;
    let n = gl.points();
    let points = grid_points(xyz, &gl, xyz_path)?;
    let mut warnings = Vec::new();
    if gl.iblank {
        let at = gl.data_at + 3 * n * gl.prec;
        let ib = util::i32s(&xyz[at..at + 4 * n], gl.order);
        let blanked = ib.iter().filter(|&&v| v == 0).count();
        let fringe = ib.iter().filter(|&&v| v < 0).count();
        // Blanked points stay: the papers' tet counts include every cell of the grid.
        warnings.push(format!(
            "IBLANK present: {blanked} blanked points ({fringe} with negative IBLANK, i.e. overset-grid boundary points); all cells kept"
        ));
    }
    if gl.padding > 0 {
        warnings.push(format!(
            "{}: {} trailing zero bytes ignored",
            xyz_path.display(),
            gl.padding
        ));
    }

    let ql = sniff(q, q.len() as u64, FileKind::Q)
        .map_err(|e| LoadError::at(q_path, Location::Byte(e.at), e.kind))?;
    if ql.dims != gl.dims {
        return Err(LoadError::at(
            q_path,
            Location::Byte(0),
            ErrorKind::CountMismatch {
                what: format!(
                    "points of the Q grid ({}×{}×{}) vs the XYZ grid ({}×{}×{})",
                    ql.dims[0], ql.dims[1], ql.dims[2], gl.dims[0], gl.dims[1], gl.dims[2]
                ),
                expected: n as u64,
                found: ql.points() as u64,
            },
        ));
    }
    if ql.padding > 0 {
        warnings.push(format!(
            "{}: {} trailing zero bytes ignored",
            q_path.display(),
            ql.padding
        ));
    }
    let field = requested_field(options, q_path)?;
    // Skip the four reals (mach, alpha, Re, time) and their record.
    let qdata = ql.data_at + 4 * ql.prec + if ql.markers { 8 } else { 0 };
    let names = [
        "density",
        "x momentum",
        "y momentum",
        "z momentum",
        "energy",
    ];
    let needed: &[usize] = match field {
        Plot3dField::Density => &[0],
        Plot3dField::Energy => &[4],
        Plot3dField::MomentumMagnitude => &[1, 2, 3],
        Plot3dField::VelocityMagnitude => &[0, 1, 2, 3],
        Plot3dField::Pressure => &[0, 1, 2, 3, 4],
    };
    let mut qv: [Vec<f32>; 5] = Default::default();
    for &c in needed {
        let at = qdata + c * n * ql.prec;
        qv[c] = block(q, &ql, at, n);
        check_finite(
            q,
            &ql,
            at,
            &qv[c],
            &format!("{} of point", names[c]),
            q_path,
        )?;
    }
    let scalars: Vec<f32> = match field {
        Plot3dField::Density => std::mem::take(&mut qv[0]),
        Plot3dField::Energy => std::mem::take(&mut qv[4]),
        _ => (0..n)
            .map(|i| {
                let m2 = (1..4).map(|c| (qv[c][i] as f64).powi(2)).sum::<f64>();
                let v = match field {
                    Plot3dField::MomentumMagnitude => m2.sqrt(),
                    Plot3dField::VelocityMagnitude => m2.sqrt() / qv[0][i] as f64,
                    _ => (GAMMA - 1.0) * (qv[4][i] as f64 - 0.5 * m2 / qv[0][i] as f64),
                };
                v as f32
            })
            .collect(),
    };
    if let Some(i) = scalars.iter().position(|v| !v.is_finite()) {
        return Err(LoadError::at(
            q_path,
            Location::Byte((qdata + i * ql.prec) as u64),
            ErrorKind::NonFinite {
                what: format!(
                    "{} of point (density {})",
                    field.name(),
                    qv[0].get(i).copied().unwrap_or(f32::NAN)
                ),
                index: i as u64,
                value: scalars[i] as f64,
            },
        ));
    }
    let tets = structured_tets(gl.dims);
    let mut mesh = TetMesh::new(grid_name(xyz_path), points, scalars, field.name(), tets)
        .map_err(|k| LoadError::new(xyz_path, k))?;
    mesh.repair.warnings.extend(warnings);
    Ok(Dataset {
        mesh,
        volume: None,
        source: xyz_path.display().to_string(),
    })
}

/// Writes a PLOT3D XYZ + Q pair in the given layout (for tests and the fuzz seed corpus).
#[doc(hidden)]
pub fn write_test_pair(
    dims: [usize; 3],
    order: ByteOrder,
    markers: bool,
    iblank: bool,
    point: impl Fn(usize, usize, usize) -> [f32; 3],
    q: impl Fn(usize) -> [f32; 5],
) -> (Vec<u8>, Vec<u8>) {
    let n = dims[0] * dims[1] * dims[2];
    let i32b = |v: i32| {
        if order == ByteOrder::Big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let f32b = |v: f32| {
        if order == ByteOrder::Big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let record = |out: &mut Vec<u8>, body: Vec<u8>| {
        if markers {
            out.extend(i32b(body.len() as i32));
        }
        out.extend_from_slice(&body);
        if markers {
            out.extend(i32b(body.len() as i32));
        }
    };
    let head: Vec<u8> = dims.iter().flat_map(|&d| i32b(d as i32)).collect();
    let mut xyz = Vec::new();
    record(&mut xyz, head.clone());
    let mut body = Vec::new();
    let mut pts = Vec::with_capacity(n);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                pts.push(point(i, j, k));
            }
        }
    }
    for a in 0..3 {
        body.extend(pts.iter().flat_map(|p| f32b(p[a])));
    }
    if iblank {
        body.extend((0..n).flat_map(|i| i32b(if i % 7 == 3 { 0 } else { 1 })));
    }
    record(&mut xyz, body);
    let mut qf = Vec::new();
    record(&mut qf, head);
    record(
        &mut qf,
        [0.5f32, 0.0, 1e6, 0.0]
            .iter()
            .flat_map(|&v| f32b(v))
            .collect(),
    );
    let qs: Vec<[f32; 5]> = (0..n).map(&q).collect();
    let mut body = Vec::new();
    for c in 0..5 {
        body.extend(qs.iter().flat_map(|v| f32b(v[c])));
    }
    record(&mut qf, body);
    (xyz, qf)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair(order: ByteOrder, markers: bool, iblank: bool) -> (Vec<u8>, Vec<u8>) {
        write_test_pair(
            [3, 4, 2],
            order,
            markers,
            iblank,
            |i, j, k| [i as f32, j as f32 * 0.5, k as f32 * 2.0],
            |p| [1.0 + p as f32, 2.0, 3.0, 6.0, 100.0],
        )
    }

    fn load_pair(x: &[u8], q: &[u8], field: Option<Plot3dField>) -> Result<Dataset, LoadError> {
        let opts = LoadOptions {
            plot3d_field: field,
            ..Default::default()
        };
        from_bytes(
            x,
            q,
            Path::new("gridxyz.bin"),
            Path::new("gridq.bin"),
            &opts,
        )
    }

    #[test]
    fn all_layouts_read_the_same_grid() {
        for order in [ByteOrder::Big, ByteOrder::Little] {
            for markers in [false, true] {
                for iblank in [false, true] {
                    let (x, q) = pair(order, markers, iblank);
                    let ds = load_pair(&x, &q, None)
                        .unwrap_or_else(|e| panic!("{order:?} {markers} {iblank}: {e}"));
                    assert_eq!(ds.mesh.num_points(), 24);
                    assert_eq!(ds.mesh.num_tets(), 2 * 3 * 5);
                    assert_eq!(ds.mesh.name, "grid");
                    assert_eq!(ds.mesh.points[23], [2.0, 1.5, 2.0]);
                    assert_eq!(ds.mesh.scalars[5], 6.0);
                    let w = ds
                        .mesh
                        .repair
                        .warnings
                        .iter()
                        .any(|w| w.starts_with("IBLANK present: 3 blanked points"));
                    assert_eq!(w, iblank, "{:?}", ds.mesh.repair.warnings);
                }
            }
        }
    }

    #[test]
    fn q_fields() {
        let (x, q) = pair(ByteOrder::Big, false, false);
        let get = |f| load_pair(&x, &q, Some(f)).unwrap().mesh.scalars[1] as f64;
        // Point 1: ρ = 2, m = (2, 3, 6) (|m| = 7), E = 100.
        assert_eq!(get(Plot3dField::Density), 2.0);
        assert_eq!(get(Plot3dField::MomentumMagnitude), 7.0);
        assert_eq!(get(Plot3dField::Energy), 100.0);
        assert_eq!(get(Plot3dField::VelocityMagnitude), 3.5);
        assert!((get(Plot3dField::Pressure) - 0.4 * (100.0 - 0.5 * 49.0 / 2.0)).abs() < 1e-4);
    }

    #[test]
    fn padding_is_tolerated_and_q_names_derived() {
        let (x, mut q) = pair(ByteOrder::Big, false, false);
        q.extend([0u8; 484]);
        let ds = load_pair(&x, &q, None).unwrap();
        assert!(ds
            .mesh
            .repair
            .warnings
            .iter()
            .any(|w| w.contains("484 trailing zero bytes")));
        q.push(7);
        let err = load_pair(&x, &q, None).unwrap_err();
        assert!(matches!(err.kind, ErrorKind::CountMismatch { .. }), "{err}");
        assert_eq!(err.path, Path::new("gridq.bin"));
        assert_eq!(
            q_path_for(Path::new("/d/bluntfinxyz.bin")).unwrap(),
            Path::new("/d/bluntfinq.bin")
        );
        assert_eq!(
            q_path_for(Path::new("post.xyz")).unwrap(),
            Path::new("post.q")
        );
        assert_eq!(
            q_path_for(Path::new("wing.x")).unwrap(),
            Path::new("wing.q")
        );
        assert!(q_path_for(Path::new("wing.dat")).is_none());
    }

    #[test]
    fn data_in_the_other_byte_order_is_detected() {
        let (mut x, q) = pair(ByteOrder::Big, false, false);
        // Coordinates written little-endian under a big-endian header, one of them NaN when
        // read big-endian (and a finite denormal little-endian).
        for c in x[12..].chunks_exact_mut(4) {
            c.reverse();
        }
        x[16..20].copy_from_slice(&[0x7f, 0xc0, 0x00, 0x00]);
        let err = load_pair(&x, &q, None).unwrap_err();
        assert!(matches!(err.kind, ErrorKind::ByteOrder(_)), "{err}");
        assert_eq!(err.location, Some(Location::Byte(16)));
        // A lone NaN in sane big-endian data is a NaN, not a byte-order problem.
        let (mut x, q) = pair(ByteOrder::Big, false, false);
        x[16..20].copy_from_slice(&f32::NAN.to_be_bytes());
        let err = load_pair(&x, &q, None).unwrap_err();
        assert!(
            matches!(err.kind, ErrorKind::NonFinite { index: 1, .. }),
            "{err}"
        );
    }

    // Quick stand-in for the PLOT3D fuzz target (datasets/fuzz) that CI runs every time:
    // corrupted bytes (headers, markers, data) in every layout give a mesh or an error.
    proptest::proptest! {
        #[test]
        fn corrupted_pairs_never_panic(
            layout in 0usize..8,
            field in 0usize..5,
            edits in proptest::collection::vec((proptest::prelude::any::<bool>(), 0usize..64, proptest::prelude::any::<u8>()), 1..6),
            cut in proptest::option::of(0usize..2000),
        ) {
            let (mut x, mut q) = pair(if layout & 1 == 0 { ByteOrder::Big } else { ByteOrder::Little }, layout & 2 != 0, layout & 4 != 0);
            for (in_q, at, v) in edits {
                // Mostly the headers and markers, where the sniffing decides.
                let f = if in_q { &mut q } else { &mut x };
                let i = at % f.len();
                f[i] = v;
            }
            if let Some(c) = cut {
                x.truncate(c.min(x.len()));
            }
            let opts = LoadOptions { plot3d_field: Some(Plot3dField::ALL[field]), ..Default::default() };
            let _ = from_bytes(&x, &q, Path::new("axyz.bin"), Path::new("aq.bin"), &opts);
        }
    }
}
