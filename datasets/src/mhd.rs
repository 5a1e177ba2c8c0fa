//! MetaImage (`.mhd` header + raw data file, or `.mha` with the data after the header): 3-D
//! images of MET_UCHAR, MET_CHAR, MET_SHORT, MET_USHORT, MET_INT, MET_UINT, MET_FLOAT or
//! MET_DOUBLE, optionally zlib-compressed (`CompressedData = True`). The image is kept as a
//! [`VoxelGrid`] and converted to tets with [`structured_tets`].

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::dataset::{Dataset, LoadOptions};
use crate::error::{ErrorKind, LoadError, Location};
use crate::read_util::{self as util, ByteOrder};
use crate::volume::{structured_tets, VoxelGrid};
use crate::TetMesh;

/// Name of the image scalar.
pub const SCALAR_NAME: &str = "intensity";

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ElementType {
    U8,
    I8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl ElementType {
    fn size(self) -> usize {
        match self {
            ElementType::U8 | ElementType::I8 => 1,
            ElementType::I16 | ElementType::U16 => 2,
            ElementType::I32 | ElementType::U32 | ElementType::F32 => 4,
            ElementType::F64 => 8,
        }
    }
}

/// The parsed header.
#[derive(Debug)]
struct Header {
    dims: [u64; 3],
    spacing: [f64; 3],
    origin: [f64; 3],
    element: ElementType,
    order: ByteOrder,
    compressed: bool,
    header_size: i64,
    /// `None` for LOCAL (data follows the header in the same file) and the offset it starts at.
    data_file: Result<PathBuf, usize>,
    warnings: Vec<String>,
}

fn parse_bool(v: &str) -> Option<bool> {
    match v.to_ascii_lowercase().as_str() {
        "true" | "1" => Some(true),
        "false" | "0" => Some(false),
        _ => None,
    }
}

/// The element type a MetaImage `ElementType` value names, if it is one this reader reads.
fn element_type(value: &str) -> Option<ElementType> {
    Some(match value.to_ascii_uppercase().as_str() {
        "MET_UCHAR" => ElementType::U8,
        "MET_CHAR" => ElementType::I8,
        "MET_SHORT" => ElementType::I16,
        "MET_USHORT" => ElementType::U16,
        "MET_INT" => ElementType::I32,
        "MET_UINT" => ElementType::U32,
        "MET_FLOAT" => ElementType::F32,
        "MET_DOUBLE" => ElementType::F64,
        _ => return None,
    })
}

fn parse_header(b: &[u8], path: &Path) -> Result<Header, LoadError> {
    let mut ndims = None;
    let mut dims = None;
    let mut spacing = None;
    let mut size = None;
    let mut origin = None;
    let mut element = None;
    let mut order = ByteOrder::Little;
    let mut compressed = false;
    let mut header_size = 0i64;
    let mut data_file = None;
    let mut warnings = Vec::new();
    let mut pos = 0usize;
    let mut line_no = 0usize;
    while pos < b.len() {
        line_no += 1;
        let end = b[pos..]
            .iter()
            .position(|&c| c == b'\n')
            .map_or(b.len(), |i| pos + i);
        let raw = &b[pos..end];
        pos = (end + 1).min(b.len());
        let err = |kind| LoadError::at(path, Location::Line(line_no), kind);
        let text = std::str::from_utf8(raw).map_err(|_| {
            err(ErrorKind::Syntax {
                expected: "a \"Key = Value\" text line".into(),
                found: String::from_utf8_lossy(&raw[..raw.len().min(40)]).into_owned(),
            })
        })?;
        let line = text.trim();
        if line.is_empty() || line.starts_with('%') || line.starts_with('#') {
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            return Err(err(ErrorKind::Syntax {
                expected: "\"Key = Value\"".into(),
                found: line.chars().take(40).collect(),
            }));
        };
        let (key, value) = (key.trim(), value.trim());
        let syntax = |expected: &str| {
            err(ErrorKind::Syntax {
                expected: format!("{key}: {expected}"),
                found: value.chars().take(40).collect(),
            })
        };
        let reals = |n: usize| -> Result<Vec<f64>, LoadError> {
            let v: Vec<f64> = value
                .split_whitespace()
                .map(|t| t.parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| syntax(&format!("{n} numbers")))?;
            if v.len() < n || v.iter().any(|x| !x.is_finite()) {
                return Err(syntax(&format!("{n} finite numbers")));
            }
            Ok(v)
        };
        match key.to_ascii_lowercase().as_str() {
            "objecttype" if !value.eq_ignore_ascii_case("image") => {
                    return Err(err(ErrorKind::Unsupported(format!("MetaImage ObjectType {value} (only Image)"))));
            }
            "ndims" => {
                let n: u32 = value.parse().map_err(|_| syntax("an integer"))?;
                if n != 3 {
                    return Err(err(ErrorKind::Unsupported(format!("NDims = {n}: only 3-D images become tets"))));
                }
                ndims = Some(n);
            }
            "dimsize" => {
                let v: Vec<u64> = value.split_whitespace().map(|t| t.parse::<u64>()).collect::<Result<_, _>>().map_err(|_| syntax("3 positive integers"))?;
                if v.len() != 3 || v.contains(&0) {
                    return Err(syntax("3 positive integers"));
                }
                let d = [v[0], v[1], v[2]];
                util::grid_count(d).map_err(err)?;
                dims = Some(d);
            }
            "elementspacing" => spacing = Some(reals(3)?),
            "elementsize" => size = Some(reals(3)?),
            "offset" | "origin" | "position" => origin = Some(reals(3)?),
            "elementtype" => {
                element = Some(element_type(value).ok_or_else(|| err(ErrorKind::Unsupported(format!("ElementType {value} (MET_UCHAR, MET_CHAR, MET_SHORT, MET_USHORT, MET_INT, MET_UINT, MET_FLOAT, MET_DOUBLE are read)"))))?)
            }
            "binarydatabyteordermsb" | "elementbyteordermsb" => {
                order = if parse_bool(value).ok_or_else(|| syntax("True or False"))? { ByteOrder::Big } else { ByteOrder::Little }
            }
            "compresseddata" => compressed = parse_bool(value).ok_or_else(|| syntax("True or False"))?,
            "binarydata" if !parse_bool(value).ok_or_else(|| syntax("True or False"))? => {
                    return Err(err(ErrorKind::Unsupported("BinaryData = False (ASCII MetaImage data)".into())));
            }
            "elementnumberofchannels" if value != "1" => {
                    return Err(err(ErrorKind::Unsupported(format!("ElementNumberOfChannels = {value} (only scalar images)"))));
            }
            "headersize" => header_size = value.parse().map_err(|_| syntax("an integer"))?,
            "transformmatrix" | "rotation" | "orientation" => {
                let m = reals(9)?;
                let identity = [1., 0., 0., 0., 1., 0., 0., 0., 1.];
                if m.iter().zip(identity).any(|(a, b)| (a - b).abs() > 1e-9) {
                    warnings.push(format!("{key} is not the identity: ignored (the grid is axis-aligned)"));
                }
            }
            "elementdatafile" => {
                // Must be the last key: the data (if LOCAL) follows at once.
                if value.eq_ignore_ascii_case("LOCAL") {
                    data_file = Some(Err(pos));
                } else if value.eq_ignore_ascii_case("LIST") || value.contains('%') {
                    return Err(err(ErrorKind::Unsupported(format!("ElementDataFile = {value} (one data file per image only)"))));
                } else {
                    data_file = Some(Ok(path.parent().unwrap_or(Path::new("")).join(value)));
                }
                break;
            }
            _ => {} // AnatomicalOrientation, CenterOfRotation, ElementMin/Max, Comment…
        }
    }
    let missing = |key: &str| {
        LoadError::at(
            path,
            Location::Line(line_no.max(1)),
            ErrorKind::Truncated {
                expected: format!("the MetaImage key {key}"),
            },
        )
    };
    ndims.ok_or_else(|| missing("NDims"))?;
    let dims = dims.ok_or_else(|| missing("DimSize"))?;
    let element = element.ok_or_else(|| missing("ElementType"))?;
    let data_file = data_file.ok_or_else(|| missing("ElementDataFile"))?;
    let s = spacing.or(size).unwrap_or_else(|| vec![1.0; 3]);
    let o = origin.unwrap_or_else(|| vec![0.0; 3]);
    Ok(Header {
        dims,
        spacing: [s[0], s[1], s[2]],
        origin: [o[0], o[1], o[2]],
        element,
        order,
        compressed,
        header_size,
        data_file,
        warnings,
    })
}

fn convert(raw: &[u8], e: ElementType, order: ByteOrder) -> Vec<f32> {
    macro_rules! conv {
        ($t:ty, $n:expr) => {
            raw.chunks_exact($n)
                .map(|c| {
                    let a: [u8; $n] = c.try_into().unwrap_or([0; $n]);
                    (match order {
                        ByteOrder::Big => <$t>::from_be_bytes(a),
                        ByteOrder::Little => <$t>::from_le_bytes(a),
                    }) as f32
                })
                .collect()
        };
    }
    match e {
        ElementType::U8 => raw.iter().map(|&v| v as f32).collect(),
        ElementType::I8 => raw.iter().map(|&v| v as i8 as f32).collect(),
        ElementType::I16 => conv!(i16, 2),
        ElementType::U16 => conv!(u16, 2),
        ElementType::I32 => conv!(i32, 4),
        ElementType::U32 => conv!(u32, 4),
        ElementType::F32 => util::f32s(raw, order),
        ElementType::F64 => conv!(f64, 8),
    }
}

/// Reads a MetaImage header and its data.
pub fn read(path: &Path, options: &LoadOptions) -> Result<Dataset, LoadError> {
    check_scalar(path, options)?;
    let header_bytes = util::read_file(path)?;
    let h = parse_header(&header_bytes, path)?;
    let (dims, need) = image_size(&h, path)?;
    // The data: its own file or the rest of this one; the size is checked before reading.
    match h.data_file.clone() {
        Err(local_at) => decode(path, h, dims, need, path, &header_bytes, local_at),
        Ok(p) => {
            let meta = std::fs::metadata(&p).map_err(|e| {
                LoadError::new(
                    &p,
                    ErrorKind::Io(format!(
                        "the MetaImage data file named by {}: {e}",
                        path.display()
                    )),
                )
            })?;
            if !h.compressed && meta.len() < need as u64 {
                return Err(truncated_data_file(&p, &h, dims, need, meta.len()));
            }
            let data = util::read_file(&p)?;
            decode(path, h, dims, need, &p, &data, 0)
        }
    }
}

/// The in-memory twin of [`read`] (used by the fuzz target): `header` is the `.mhd`/`.mha`
/// file at `path`; `data` stands for the contents of the data file the header names (ignored
/// when the header says `ElementDataFile = LOCAL`, whose data follows the header).
pub fn from_bytes(
    header: &[u8],
    data: &[u8],
    path: &Path,
    options: &LoadOptions,
) -> Result<Dataset, LoadError> {
    check_scalar(path, options)?;
    let h = parse_header(header, path)?;
    let (dims, need) = image_size(&h, path)?;
    match h.data_file.clone() {
        Err(local_at) => decode(path, h, dims, need, path, header, local_at),
        Ok(p) => {
            if !h.compressed && (data.len() as u64) < need as u64 {
                return Err(truncated_data_file(&p, &h, dims, need, data.len() as u64));
            }
            decode(path, h, dims, need, &p, data, 0)
        }
    }
}

/// The image has one scalar, [`SCALAR_NAME`]: any other requested name is an error.
fn check_scalar(path: &Path, options: &LoadOptions) -> Result<(), LoadError> {
    match &options.scalar {
        Some(name) if name != SCALAR_NAME => Err(LoadError::new(
            path,
            ErrorKind::MissingArray {
                name: name.clone(),
                available: vec![SCALAR_NAME.into()],
            },
        )),
        _ => Ok(()),
    }
}

/// The grid dimensions and the byte count of the uncompressed image data.
fn image_size(h: &Header, path: &Path) -> Result<([usize; 3], usize), LoadError> {
    let n = util::grid_count(h.dims).map_err(|k| LoadError::new(path, k))?;
    let dims = h.dims.map(|d| d as usize);
    if dims.iter().any(|&d| d < 2) {
        return Err(LoadError::new(
            path,
            ErrorKind::EmptyMesh(format!(
                " (a {}×{}×{} image has no 3-D cells)",
                dims[0], dims[1], dims[2]
            )),
        ));
    }
    Ok((dims, n * h.element.size()))
}

fn truncated_data_file(p: &Path, h: &Header, dims: [usize; 3], need: usize, len: u64) -> LoadError {
    LoadError::at(
        p,
        Location::Byte(len),
        ErrorKind::Truncated {
            expected: format!(
                "{need} bytes of {:?} for a {}×{}×{} image, the file has {len}",
                h.element, dims[0], dims[1], dims[2],
            ),
        },
    )
}

/// Decodes the image data (`bytes[start..]`, from `data_path`) and builds the data set of the
/// header at `path`.
fn decode(
    path: &Path,
    mut h: Header,
    dims: [usize; 3],
    need: usize,
    data_path: &Path,
    bytes: &[u8],
    start: usize,
) -> Result<Dataset, LoadError> {
    let avail = bytes.len() - start;
    let raw: std::borrow::Cow<[u8]> = if h.compressed {
        let mut out = Vec::with_capacity(need.min(avail.saturating_mul(64)));
        flate2::read::ZlibDecoder::new(&bytes[start..])
            .take(need as u64 + 1)
            .read_to_end(&mut out)
            .map_err(|e| {
                LoadError::at(
                    data_path,
                    Location::Byte(start as u64),
                    ErrorKind::Invalid(format!("zlib data: {e}")),
                )
            })?;
        if out.len() != need {
            let kind = if out.len() < need {
                ErrorKind::Truncated {
                    expected: format!("{need} decompressed bytes, got {}", out.len()),
                }
            } else {
                ErrorKind::CountMismatch {
                    what: "decompressed bytes".into(),
                    expected: need as u64,
                    found: out.len() as u64,
                }
            };
            return Err(LoadError::at(data_path, Location::Byte(start as u64), kind));
        }
        std::borrow::Cow::Owned(out)
    } else {
        // HeaderSize = -1: the data is the last `need` bytes.
        let off = if h.header_size < 0 {
            bytes.len().saturating_sub(need)
        } else {
            start.saturating_add(h.header_size as usize)
        };
        if off > bytes.len() || bytes.len() - off < need {
            return Err(LoadError::at(
                data_path,
                Location::Byte(bytes.len() as u64),
                ErrorKind::Truncated {
                    expected: format!(
                        "{need} bytes of {:?} image data from byte {off}, the file has {}",
                        h.element,
                        bytes.len()
                    ),
                },
            ));
        }
        if bytes.len() - off > need && h.header_size >= 0 {
            h.warnings.push(format!(
                "{}: {} bytes after the image data ignored",
                data_path.display(),
                bytes.len() - off - need
            ));
        }
        std::borrow::Cow::Borrowed(&bytes[off..off + need])
    };
    let values = convert(&raw, h.element, h.order);
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        let other = if h.order == ByteOrder::Big {
            ByteOrder::Little
        } else {
            ByteOrder::Big
        };
        let kind = if util::looks_byte_swapped(&values, &convert(&raw, h.element, other)) {
            ErrorKind::ByteOrder(format!("voxel {i} is {} with the header's byte order ({:?}-endian) but the data reads as sane values in the other order: fix BinaryDataByteOrderMSB", values[i], h.order))
        } else {
            ErrorKind::NonFinite {
                what: "voxel".into(),
                index: i as u64,
                value: values[i] as f64,
            }
        };
        return Err(LoadError::at(
            data_path,
            Location::Byte((i * h.element.size()) as u64),
            kind,
        ));
    }
    let points = util::grid_points(dims, h.origin, h.spacing);
    let volume = VoxelGrid {
        dims,
        spacing: h.spacing,
        origin: h.origin,
        values: values.clone().into(),
        scalar_name: SCALAR_NAME.into(),
    };
    let mut mesh = TetMesh::new(
        util::stem_name(path),
        points,
        values,
        SCALAR_NAME,
        structured_tets(dims),
    )
    .map_err(|k| LoadError::new(path, k))?;
    mesh.repair.warnings.extend(h.warnings);
    Ok(Dataset {
        mesh,
        volume: Some(std::sync::Arc::new(volume)),
        source: path.display().to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn types_orders_and_local_data() {
        let dir = tempfile::tempdir().unwrap();
        let vals: Vec<f32> = (0..2 * 3 * 2).map(|i| i as f32 * 10.0).collect();
        let cases: [(&str, Vec<u8>, bool); 4] = [
            ("MET_UCHAR", vals.iter().map(|&v| v as u8).collect(), false),
            (
                "MET_SHORT",
                vals.iter()
                    .flat_map(|&v| (v as i16).to_be_bytes())
                    .collect(),
                true,
            ),
            (
                "MET_USHORT",
                vals.iter()
                    .flat_map(|&v| (v as u16).to_le_bytes())
                    .collect(),
                false,
            ),
            (
                "MET_FLOAT",
                vals.iter().flat_map(|&v| v.to_be_bytes()).collect(),
                true,
            ),
        ];
        for (ty, raw, msb) in cases {
            write(dir.path(), "img.raw", &raw);
            let hdr = format!("ObjectType = Image\nNDims = 3\nDimSize = 2 3 2\nElementSpacing = 1 2 3\nOffset = 5 0 0\nElementType = {ty}\nBinaryDataByteOrderMSB = {}\nElementDataFile = img.raw\n", if msb { "True" } else { "False" });
            let p = write(dir.path(), "img.mhd", hdr.as_bytes());
            let ds = read(&p, &LoadOptions::default()).unwrap_or_else(|e| panic!("{ty}: {e}"));
            assert_eq!(ds.mesh.scalars, vals, "{ty}");
            assert_eq!(ds.mesh.num_tets(), 2 * 5);
            assert_eq!(ds.mesh.points[11], [6.0, 4.0, 3.0]);
            assert_eq!(ds.volume.unwrap().dims, [2, 3, 2]);
        }
        // .mha: data after the header.
        let mut mha =
            b"NDims = 3\nDimSize = 2 3 2\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n"
                .to_vec();
        mha.extend(vals.iter().map(|&v| v as u8));
        let p = write(dir.path(), "img.mha", &mha);
        assert_eq!(
            read(&p, &LoadOptions::default()).unwrap().mesh.scalars,
            vals
        );
    }

    #[test]
    fn wrong_byte_order_flag_is_reported() {
        let dir = tempfile::tempdir().unwrap();
        // Little-endian floats declared big-endian: small floats reversed are denormals, and one
        // value is NaN only in the declared order.
        let vals: Vec<f32> = (0..8).map(|i| 1.0 + i as f32).collect();
        let mut raw: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
        raw[0..4].copy_from_slice(&[0x7f, 0xc0, 0x00, 0x00]); // NaN big-endian, a denormal LE
        write(dir.path(), "f.raw", &raw);
        let p = write(dir.path(), "f.mhd", b"NDims = 3\nDimSize = 2 2 2\nElementType = MET_FLOAT\nBinaryDataByteOrderMSB = True\nElementDataFile = f.raw\n");
        let err = read(&p, &LoadOptions::default()).unwrap_err();
        assert!(matches!(err.kind, ErrorKind::ByteOrder(_)), "{err}");
        assert_eq!(err.path, dir.path().join("f.raw"));
    }

    /// The fuzz target's seeds, split as the target splits them (first two bytes: the header
    /// length), all read, and `from_bytes` agrees with `read` on files.
    #[test]
    fn fuzz_seeds_read_in_memory() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/mhd");
        let mut n = 0;
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            let b = std::fs::read(&p).unwrap();
            let rest = &b[2..];
            let split = u16::from_le_bytes([b[0], b[1]]) as usize % (rest.len() + 1);
            let (header, data) = rest.split_at(split);
            let ds = from_bytes(header, data, Path::new("seed.mhd"), &LoadOptions::default())
                .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            assert_eq!(
                ds.mesh.num_points(),
                ds.volume.as_ref().unwrap().num_voxels()
            );
            // The same bytes as files.
            let tmp = tempfile::tempdir().unwrap();
            let text = String::from_utf8_lossy(header);
            let data_name = text
                .lines()
                .find_map(|l| l.strip_prefix("ElementDataFile = "))
                .unwrap();
            if data_name != "LOCAL" {
                write(tmp.path(), data_name, data);
            }
            let hp = write(tmp.path(), "seed.mhd", header);
            assert_eq!(
                read(&hp, &LoadOptions::default()).unwrap().mesh.scalars,
                ds.mesh.scalars
            );
            n += 1;
        }
        assert_eq!(n, 12);
    }
}
