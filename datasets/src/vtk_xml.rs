//! VTK XML reader: `.vtu` (UnstructuredGrid), `.vts` (StructuredGrid) and `.vti` (ImageData).
//!
//! Supports every DataArray layout VTK and ParaView write: `ascii`, inline `binary` (base64,
//! optionally zlib-compressed with `vtkZLibDataCompressor` block headers) and `appended` data
//! (`encoding="raw"` or `"base64"`), `header_type` UInt32/UInt64, either `byte_order`, and all
//! numeric element types. The XML structure is parsed with quick-xml; the raw appended section
//! is binary (it may contain `<` and invalid UTF-8), so it is cut off before the XML parser
//! sees it and addressed by the arrays' `offset` attributes, as VTK itself does.
//!
//! Hand-written rather than vtkio (which checks it: `tests/vtkio_oracle.rs`): vtkio 0.7.0-rc2
//! refuses raw appended data, ParaView's and our writer's default layout, and its errors carry
//! no position (measurements in the README, "Dependencies").
//!
//! Non-tetrahedral cells are split into conforming tets by [`crate::cells::cell_to_tets`] (shared
//! with the legacy reader); cell data is
//! averaged to the points when a file has no point data (with a warning in the repair report).

use std::borrow::Cow;
use std::io::Read;
use std::path::Path;

use base64::Engine;
use quick_xml::events::{BytesStart, Event};
use rayon::prelude::*;

use crate::error::{ErrorKind, LoadError, Location};
use crate::dataset::{Dataset, LoadOptions};
use crate::mesh::TetMesh;
use crate::volume::{structured_tets, VoxelGrid};

/// Reads a `.vtu`, `.vts` or `.vti` file (the dataset type comes from the file's `type`
/// attribute, not the extension).
pub fn read(path: &Path, options: &LoadOptions) -> Result<Dataset, LoadError> {
    let bytes =
        std::fs::read(path).map_err(|e| LoadError::new(path, ErrorKind::Io(e.to_string())))?;
    from_bytes(&bytes, path, options)
}

/// Parses VTK XML content held in memory; `path` names it in errors and gives the mesh name.
pub fn from_bytes(bytes: &[u8], path: &Path, options: &LoadOptions) -> Result<Dataset, LoadError> {
    let file = XmlFile::parse(bytes, path)?;
    file.build(options)
}

// ---------------------------------------------------------------------------------------------
// A minimal element tree (the XML part of a VTK file is small; array payloads are kept as text
// or addressed in the appended block).

#[derive(Debug, Default)]
struct Element {
    name: String,
    attrs: Vec<(String, String)>,
    children: Vec<Element>,
    /// Concatenated text content (only arrays carry any that matters).
    text: Vec<u8>,
    /// Byte offset of the start tag and of the first text.
    pos: u64,
    text_pos: u64,
}

impl Element {
    fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
    fn child(&self, name: &str) -> Option<&Element> {
        self.children.iter().find(|c| c.name == name)
    }
    fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
}

/// Where the appended block lives and how it is encoded.
enum Appended<'a> {
    /// Raw bytes after the `_` marker, and their offset in the file.
    Raw(&'a [u8], u64),
    /// Base64 text after the `_` marker (without trailing whitespace), and its offset.
    Base64(&'a [u8], u64),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum NumType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl NumType {
    fn parse(s: &str) -> Option<NumType> {
        Some(match s {
            "Int8" | "Char" => NumType::I8,
            "UInt8" | "UnsignedChar" => NumType::U8,
            "Int16" | "Short" => NumType::I16,
            "UInt16" | "UnsignedShort" => NumType::U16,
            "Int32" | "Int" => NumType::I32,
            "UInt32" | "UnsignedInt" => NumType::U32,
            "Int64" | "Long" | "LongLong" | "IdType" => NumType::I64,
            "UInt64" | "UnsignedLong" | "UnsignedLongLong" => NumType::U64,
            "Float32" | "Float" => NumType::F32,
            "Float64" | "Double" => NumType::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            NumType::I8 | NumType::U8 => 1,
            NumType::I16 | NumType::U16 => 2,
            NumType::I32 | NumType::U32 | NumType::F32 => 4,
            NumType::I64 | NumType::U64 | NumType::F64 => 8,
        }
    }
    fn is_float(self) -> bool {
        matches!(self, NumType::F32 | NumType::F64)
    }
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

fn rfind(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).rposition(|w| w == needle)
}

/// A parsed file: the element tree plus the settings that govern how arrays decode.
struct XmlFile<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    root: Element,
    big_endian: bool,
    header64: bool,
    compressed: bool,
    appended: Option<Appended<'a>>,
}

impl<'a> XmlFile<'a> {
    fn parse(bytes: &'a [u8], path: &'a Path) -> Result<XmlFile<'a>, LoadError> {
        // Cut the appended block off before XML parsing: raw binary is not XML text.
        let mut xml_end = bytes.len();
        let mut data_start = None;
        if let Some(s) = find(bytes, b"<AppendedData") {
            let gt = find(&bytes[s..], b">").map(|g| s + g).ok_or_else(|| {
                LoadError::at(
                    path,
                    Location::Byte(s as u64),
                    ErrorKind::Truncated {
                        expected: "end of the <AppendedData> tag".into(),
                    },
                )
            })?;
            xml_end = gt + 1;
            let mut i = gt + 1;
            while i < bytes.len() && bytes[i].is_ascii_whitespace() {
                i += 1;
            }
            if i >= bytes.len() || bytes[i] != b'_' {
                return Err(LoadError::at(
                    path,
                    Location::Byte(i as u64),
                    ErrorKind::Syntax {
                        expected: "'_' marking the start of the appended data".into(),
                        found: bytes
                            .get(i)
                            .map(|&b| (b as char).to_string())
                            .unwrap_or_else(|| "end of file".into()),
                    },
                ));
            }
            data_start = Some(i + 1);
        }
        let root = parse_tree(&bytes[..xml_end], path, data_start.is_some())?;
        let vtk = root.child("VTKFile").ok_or_else(|| {
            LoadError::at(
                path,
                Location::Line(1),
                ErrorKind::Syntax {
                    expected: "a <VTKFile> root element".into(),
                    found: first_name(&root),
                },
            )
        })?;
        let big_endian = match vtk.attr("byte_order") {
            None | Some("LittleEndian") => false,
            Some("BigEndian") => true,
            Some(other) => {
                return Err(LoadError::at(
                    path,
                    Location::Line(line_of(bytes, vtk.pos)),
                    ErrorKind::ByteOrder(format!(
                        "byte_order must be LittleEndian or BigEndian, found {other:?}"
                    )),
                ))
            }
        };
        let header64 = match vtk.attr("header_type") {
            None | Some("UInt32") => false,
            Some("UInt64") => true,
            Some(other) => {
                return Err(LoadError::at(
                    path,
                    Location::Line(line_of(bytes, vtk.pos)),
                    ErrorKind::Syntax {
                        expected: "header_type UInt32 or UInt64".into(),
                        found: other.into(),
                    },
                ))
            }
        };
        let compressed = match vtk.attr("compressor") {
            None | Some("") => false,
            Some("vtkZLibDataCompressor") => true,
            Some(other) => {
                return Err(LoadError::at(
                    path,
                    Location::Line(line_of(bytes, vtk.pos)),
                    ErrorKind::Unsupported(format!(
                        "compressor {other} (only vtkZLibDataCompressor is supported)"
                    )),
                ))
            }
        };
        let appended = match data_start {
            None => None,
            Some(start) => {
                let el = vtk.child("AppendedData");
                match el.and_then(|e| e.attr("encoding")).unwrap_or("raw") {
                    "raw" => Some(Appended::Raw(&bytes[start..], start as u64)),
                    "base64" => {
                        let end = rfind(&bytes[start..], b"</AppendedData>")
                            .map(|e| start + e)
                            .unwrap_or(bytes.len());
                        let text = bytes[start..end].trim_ascii_end();
                        Some(Appended::Base64(text, start as u64))
                    }
                    other => {
                        return Err(LoadError::at(
                            path,
                            Location::Byte(start as u64),
                            ErrorKind::Syntax {
                                expected: "AppendedData encoding raw or base64".into(),
                                found: other.into(),
                            },
                        ))
                    }
                }
            }
        };
        Ok(XmlFile {
            path,
            bytes,
            root,
            big_endian,
            header64,
            compressed,
            appended,
        })
    }

    fn err_el(&self, el: &Element, kind: ErrorKind) -> LoadError {
        LoadError::at(self.path, Location::Line(line_of(self.bytes, el.pos)), kind)
    }

    fn vtk(&self) -> &Element {
        // `parse` checked that it exists.
        self.root
            .child("VTKFile")
            .expect("VTKFile checked in parse")
    }

    fn build(&self, options: &LoadOptions) -> Result<Dataset, LoadError> {
        let vtk = self.vtk();
        let ty = vtk.attr("type").unwrap_or("");
        match ty {
            "UnstructuredGrid" | "StructuredGrid" | "ImageData" => {}
            "" => return Err(self.err_el(vtk, ErrorKind::Syntax { expected: "a type attribute on <VTKFile>".into(), found: String::new() })),
            other => {
                return Err(self.err_el(
                    vtk,
                    ErrorKind::Unsupported(format!("VTK XML dataset type {other} (supported: UnstructuredGrid, StructuredGrid, ImageData)")),
                ))
            }
        }
        let grid = vtk.child(ty).ok_or_else(|| {
            self.err_el(
                vtk,
                ErrorKind::Syntax {
                    expected: format!("a <{ty}> element inside <VTKFile>"),
                    found: first_name(vtk),
                },
            )
        })?;
        if ty == "UnstructuredGrid" {
            self.build_unstructured(grid, options)
        } else {
            self.build_structured(grid, ty == "ImageData", options)
        }
    }

    fn mesh_name(&self) -> String {
        self.path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "vtk".into())
    }

    fn attr_usize(&self, el: &Element, key: &str) -> Result<usize, LoadError> {
        let v = el.attr(key).ok_or_else(|| {
            self.err_el(
                el,
                ErrorKind::Syntax {
                    expected: format!("attribute {key} on <{}>", el.name),
                    found: "nothing".into(),
                },
            )
        })?;
        v.trim().parse::<usize>().map_err(|_| {
            self.err_el(
                el,
                ErrorKind::Syntax {
                    expected: format!("a non-negative integer {key}"),
                    found: v.into(),
                },
            )
        })
    }

    fn attr_numbers<T: std::str::FromStr>(
        &self,
        el: &Element,
        key: &str,
        n: usize,
    ) -> Result<Option<Vec<T>>, LoadError> {
        let Some(v) = el.attr(key) else {
            return Ok(None);
        };
        let parsed: Option<Vec<T>> = v.split_ascii_whitespace().map(|t| t.parse().ok()).collect();
        match parsed {
            Some(p) if p.len() == n => Ok(Some(p)),
            _ => Err(self.err_el(
                el,
                ErrorKind::Syntax {
                    expected: format!("{n} numbers in attribute {key}"),
                    found: v.into(),
                },
            )),
        }
    }

    // -- Arrays ---------------------------------------------------------------------------------

    fn array_type(&self, el: &Element) -> Result<NumType, LoadError> {
        let t = el.attr("type").unwrap_or("");
        NumType::parse(t).ok_or_else(|| {
            self.err_el(
                el,
                ErrorKind::Unsupported(format!(
                    "DataArray type {t:?} (expected Int8..UInt64, Float32 or Float64)"
                )),
            )
        })
    }

    fn components(&self, el: &Element) -> Result<usize, LoadError> {
        match el.attr("NumberOfComponents") {
            None => Ok(1),
            Some(_) => {
                let n = self.attr_usize(el, "NumberOfComponents")?;
                if n == 0 {
                    Err(self.err_el(
                        el,
                        ErrorKind::Syntax {
                            expected: "NumberOfComponents ≥ 1".into(),
                            found: "0".into(),
                        },
                    ))
                } else {
                    Ok(n)
                }
            }
        }
    }

    /// The raw element bytes of a binary or appended array (in the file's byte order), or the
    /// text of an ascii one.
    fn payload<'s>(&'s self, el: &'s Element) -> Result<Payload<'s>, LoadError> {
        let format = el.attr("format").unwrap_or("ascii");
        match format {
            "ascii" => Ok(Payload::Text(&el.text, el.text_pos)),
            "binary" => {
                // VTK writes the base64 of an array on one line: trimming is then enough, and
                // skips a byte-by-byte copy that took half the read of Blunt Fin in base64.
                let lead = el
                    .text
                    .iter()
                    .take_while(|b| b.is_ascii_whitespace())
                    .count();
                let trimmed = el.text[lead..].trim_ascii_end();
                let text: Cow<[u8]> = if trimmed.iter().any(|b| b.is_ascii_whitespace()) {
                    let mut t = Vec::with_capacity(trimmed.len());
                    t.extend(trimmed.iter().filter(|b| !b.is_ascii_whitespace()));
                    Cow::Owned(t)
                } else {
                    Cow::Borrowed(trimmed)
                };
                let mut src = B64Source {
                    text: &text,
                    pos: 0,
                    pending: Vec::new(),
                    base: el.text_pos + lead as u64,
                };
                let bytes = self
                    .read_block(&mut src)
                    .map_err(|k| LoadError::at(self.path, Location::Byte(el.text_pos), k))?;
                Ok(Payload::Bytes(Cow::Owned(bytes.into_owned()), el.text_pos))
            }
            "appended" => {
                let offset = self.attr_usize(el, "offset")?;
                match &self.appended {
                    None => Err(self.err_el(
                        el,
                        ErrorKind::Syntax {
                            expected: "an <AppendedData> section for format=\"appended\"".into(),
                            found: "none".into(),
                        },
                    )),
                    Some(Appended::Raw(data, base)) => {
                        if offset > data.len() {
                            return Err(LoadError::at(
                                self.path,
                                Location::Byte(base + offset as u64),
                                ErrorKind::IndexOutOfRange {
                                    what: format!(
                                        "appended offset of array {:?}",
                                        el.attr("Name").unwrap_or("")
                                    ),
                                    index: offset as u64,
                                    limit: data.len() as u64,
                                },
                            ));
                        }
                        let mut src = RawSource {
                            data: &data[offset..],
                            pos: 0,
                            base: base + offset as u64,
                        };
                        let at = src.base;
                        let bytes = self.read_block(&mut src).map_err(|k| {
                            LoadError::at(self.path, Location::Byte(src.base + src.pos as u64), k)
                        })?;
                        Ok(Payload::Bytes(bytes, at))
                    }
                    Some(Appended::Base64(text, base)) => {
                        if offset > text.len() {
                            return Err(LoadError::at(
                                self.path,
                                Location::Byte(base + offset as u64),
                                ErrorKind::IndexOutOfRange {
                                    what: format!(
                                        "appended offset of array {:?}",
                                        el.attr("Name").unwrap_or("")
                                    ),
                                    index: offset as u64,
                                    limit: text.len() as u64,
                                },
                            ));
                        }
                        let mut src = B64Source {
                            text: &text[offset..],
                            pos: 0,
                            pending: Vec::new(),
                            base: base + offset as u64,
                        };
                        let bytes = self.read_block(&mut src).map_err(|k| {
                            LoadError::at(self.path, Location::Byte(base + offset as u64), k)
                        })?;
                        Ok(Payload::Bytes(
                            Cow::Owned(bytes.into_owned()),
                            base + offset as u64,
                        ))
                    }
                }
            }
            other => Err(self.err_el(
                el,
                ErrorKind::Syntax {
                    expected: "format ascii, binary or appended".into(),
                    found: other.into(),
                },
            )),
        }
    }

    fn read_header_int<'s, S: Source<'s>>(&self, src: &mut S) -> Result<u64, ErrorKind> {
        let n = if self.header64 { 8 } else { 4 };
        let b = src.take(n, "block header")?;
        Ok(match (self.header64, self.big_endian) {
            (false, false) => u32::from_le_bytes(b[..4].try_into().unwrap()) as u64,
            (false, true) => u32::from_be_bytes(b[..4].try_into().unwrap()) as u64,
            (true, false) => u64::from_le_bytes(b[..8].try_into().unwrap()),
            (true, true) => u64::from_be_bytes(b[..8].try_into().unwrap()),
        })
    }

    /// One binary block: a byte-count header then the bytes, or (compressed) the
    /// vtkZLibDataCompressor header `[#blocks, block size, last block size, compressed sizes…]`
    /// then the zlib streams.
    fn read_block<'s, S: Source<'s>>(&self, src: &mut S) -> Result<Cow<'s, [u8]>, ErrorKind> {
        if !self.compressed {
            let n = self.read_header_int(src)?;
            return src.take(
                usize::try_from(n).unwrap_or(usize::MAX),
                "array bytes announced by the block header",
            );
        }
        let nblocks = self.read_header_int(src)?;
        let block_size = self.read_header_int(src)?;
        let last_size = self.read_header_int(src)?;
        let mut sizes = Vec::new();
        for _ in 0..nblocks {
            sizes.push(self.read_header_int(src)?);
        }
        let mut out = Vec::new();
        for (b, &cs) in sizes.iter().enumerate() {
            let expect = if b + 1 == sizes.len() && last_size != 0 {
                last_size
            } else {
                block_size
            };
            let comp = src.take(
                usize::try_from(cs).unwrap_or(usize::MAX),
                "compressed block",
            )?;
            let start = out.len();
            // Read at most one byte more than announced so a wrong header cannot blow memory.
            let got = flate2::read::ZlibDecoder::new(&comp[..])
                .take(expect.saturating_add(1))
                .read_to_end(&mut out)
                .map_err(|e| ErrorKind::Invalid(format!("zlib block {b}: {e}")))?;
            if got as u64 != expect {
                out.truncate(start);
                return Err(ErrorKind::CountMismatch {
                    what: format!("uncompressed bytes of zlib block {b}"),
                    expected: expect,
                    found: got as u64,
                });
            }
        }
        Ok(Cow::Owned(out))
    }

    /// Decodes an array as f64 values, checking that it holds `expected` values.
    fn read_f64(&self, el: &Element, expected: usize) -> Result<Vec<f64>, LoadError> {
        let ty = self.array_type(el)?;
        let values = match self.payload(el)? {
            Payload::Text(text, pos) => parse_ascii::<f64>(text, pos, ty.is_float())
                .map_err(|(p, k)| LoadError::at(self.path, Location::Byte(p), k))?,
            Payload::Bytes(b, pos) => {
                let b = self.check_len(el, &b, ty, pos)?;
                bytes_to_f64(b, ty, self.big_endian)
            }
        };
        self.check_count(el, values.len(), expected)?;
        Ok(values)
    }

    /// Decodes an integer array as i64 values, checking that it holds `expected` values
    /// (if given).
    fn read_i64(&self, el: &Element, expected: Option<usize>) -> Result<Vec<i64>, LoadError> {
        let ty = self.array_type(el)?;
        if ty.is_float() {
            return Err(self.err_el(
                el,
                ErrorKind::Syntax {
                    expected: format!(
                        "an integer type for array {:?}",
                        el.attr("Name").unwrap_or("")
                    ),
                    found: el.attr("type").unwrap_or("").into(),
                },
            ));
        }
        let values = match self.payload(el)? {
            Payload::Text(text, pos) => parse_ascii::<i64>(text, pos, false)
                .map_err(|(p, k)| LoadError::at(self.path, Location::Byte(p), k))?,
            Payload::Bytes(b, pos) => {
                let b = self.check_len(el, &b, ty, pos)?;
                bytes_to_i64(b, ty, self.big_endian).map_err(|(i, v)| {
                    LoadError::at(
                        self.path,
                        Location::Byte(pos + (i * 8) as u64),
                        ErrorKind::IndexOutOfRange {
                            what: "UInt64 value".into(),
                            index: v,
                            limit: i64::MAX as u64,
                        },
                    )
                })?
            }
        };
        if let Some(n) = expected {
            self.check_count(el, values.len(), n)?;
        }
        Ok(values)
    }

    fn check_len<'b>(
        &self,
        el: &Element,
        b: &'b [u8],
        ty: NumType,
        pos: u64,
    ) -> Result<&'b [u8], LoadError> {
        if !b.len().is_multiple_of(ty.size()) {
            return Err(LoadError::at(
                self.path,
                Location::Byte(pos),
                ErrorKind::Invalid(format!(
                    "array {:?}: {} bytes is not a whole number of {}-byte values",
                    el.attr("Name").unwrap_or(""),
                    b.len(),
                    ty.size()
                )),
            ));
        }
        Ok(b)
    }

    fn check_count(&self, el: &Element, found: usize, expected: usize) -> Result<(), LoadError> {
        if found != expected {
            return Err(self.err_el(
                el,
                ErrorKind::CountMismatch {
                    what: format!("values in array {:?}", el.attr("Name").unwrap_or("")),
                    expected: expected as u64,
                    found: found as u64,
                },
            ));
        }
        Ok(())
    }

    // -- Scalars --------------------------------------------------------------------------------

    /// Chooses the point scalar: `options.scalar` by name, else the PointData's active
    /// `Scalars`, else its first one-component array, else its first array (as magnitude).
    /// Falls back to cell data (averaged by the caller) and finally to a zero field.
    fn choose_scalar(
        &self,
        piece: &Element,
        options: &LoadOptions,
        npoints: usize,
        ncells: usize,
    ) -> Result<ScalarSource, LoadError> {
        let pd: Vec<&Element> = piece
            .child("PointData")
            .map(|p| p.children_named("DataArray").collect())
            .unwrap_or_default();
        let cd: Vec<&Element> = piece
            .child("CellData")
            .map(|p| p.children_named("DataArray").collect())
            .unwrap_or_default();
        let name_of = |e: &Element| e.attr("Name").unwrap_or("").to_string();
        if let Some(want) = &options.scalar {
            if let Some(e) = pd.iter().find(|e| e.attr("Name") == Some(want.as_str())) {
                return Ok(ScalarSource::Point(
                    want.clone(),
                    self.read_scalar_array(e, npoints)?,
                ));
            }
            if let Some(e) = cd.iter().find(|e| e.attr("Name") == Some(want.as_str())) {
                return Ok(ScalarSource::Cell(
                    want.clone(),
                    self.read_scalar_array(e, ncells)?,
                ));
            }
            return Err(self.err_el(
                piece,
                ErrorKind::MissingArray {
                    name: want.clone(),
                    available: pd.iter().chain(cd.iter()).map(|e| name_of(e)).collect(),
                },
            ));
        }
        if let Some(i) = pick_default(&pd, piece.child("PointData")) {
            return Ok(ScalarSource::Point(
                name_of(pd[i]),
                self.read_scalar_array(pd[i], npoints)?,
            ));
        }
        if let Some(i) = pick_default(&cd, piece.child("CellData")) {
            return Ok(ScalarSource::Cell(
                name_of(cd[i]),
                self.read_scalar_array(cd[i], ncells)?,
            ));
        }
        Ok(ScalarSource::None)
    }

    /// One value per tuple; arrays of several components give their Euclidean magnitude.
    fn read_scalar_array(&self, el: &Element, tuples: usize) -> Result<Vec<f64>, LoadError> {
        let nc = self.components(el)?;
        let v = self.read_f64(el, tuples.saturating_mul(nc))?;
        if nc == 1 {
            return Ok(v);
        }
        Ok(v.chunks_exact(nc)
            .map(|c| c.iter().map(|x| x * x).sum::<f64>().sqrt())
            .collect())
    }

    // -- Datasets -------------------------------------------------------------------------------

    fn build_unstructured(
        &self,
        grid: &Element,
        options: &LoadOptions,
    ) -> Result<Dataset, LoadError> {
        let mut points: Vec<[f32; 3]> = Vec::new();
        let mut scalars: Vec<f32> = Vec::new();
        let mut tets: Vec<[u32; 4]> = Vec::new();
        let mut warnings = Vec::new();
        let mut scalar_name: Option<String> = None;
        let pieces: Vec<&Element> = grid.children_named("Piece").collect();
        if pieces.is_empty() {
            return Err(self.err_el(grid, ErrorKind::EmptyMesh(" (no <Piece>)".into())));
        }
        for piece in pieces {
            let np = self.attr_usize(piece, "NumberOfPoints")?;
            let nc = self.attr_usize(piece, "NumberOfCells")?;
            let base = points.len();
            if base.saturating_add(np) > u32::MAX as usize {
                return Err(self.err_el(
                    piece,
                    ErrorKind::IndexOverflow {
                        what: "points".into(),
                        count: base.saturating_add(np) as u64,
                    },
                ));
            }
            let pts_el = piece
                .child("Points")
                .and_then(|p| p.child("DataArray"))
                .ok_or_else(|| {
                    self.err_el(
                        piece,
                        ErrorKind::Syntax {
                            expected: "<Points><DataArray …>".into(),
                            found: "none".into(),
                        },
                    )
                })?;
            self.read_points(pts_el, np, &mut points)?;
            let cells = piece.child("Cells").ok_or_else(|| {
                self.err_el(
                    piece,
                    ErrorKind::Syntax {
                        expected: "a <Cells> element".into(),
                        found: "none".into(),
                    },
                )
            })?;
            let arr = |name: &str| {
                cells
                    .children_named("DataArray")
                    .find(|e| e.attr("Name") == Some(name))
                    .ok_or_else(|| {
                        self.err_el(
                            cells,
                            ErrorKind::Syntax {
                                expected: format!("a DataArray named {name} in <Cells>"),
                                found: "none".into(),
                            },
                        )
                    })
            };
            let (conn_el, off_el, types_el) =
                (arr("connectivity")?, arr("offsets")?, arr("types")?);
            let conn = self.read_i64(conn_el, None)?;
            let mut offsets = self.read_i64(off_el, None)?;
            let types = self.read_i64(types_el, Some(nc))?;
            // Offsets are cell *ends* (nc values); accept the nc+1 "starts" layout too.
            if offsets.len() == nc + 1 && offsets.first() == Some(&0) {
                offsets.remove(0);
            }
            self.check_count(off_el, offsets.len(), nc)?;
            let bad_point = |c: usize, v: i64| {
                self.err_el(
                    conn_el,
                    ErrorKind::IndexOutOfRange {
                        what: format!("point of cell {c}"),
                        index: v.max(0) as u64,
                        limit: np as u64,
                    },
                )
            };
            // Cell c spans conn[start(c)..offsets[c]].
            let start_of = |c: usize| if c == 0 { 0 } else { offsets[c - 1] as usize };
            let pure_tets = conn.len() == 4 * nc
                && types.par_iter().all(|&t| t == 10)
                && offsets
                    .par_iter()
                    .enumerate()
                    .all(|(c, &o)| o == 4 * (c as i64 + 1));
            if pure_tets {
                // Fast path for tet-only files (all that the writer produces): no per-cell work.
                if let Some((i, &v)) = conn
                    .par_iter()
                    .enumerate()
                    .find_first(|(_, &v)| v < 0 || v as u64 >= np as u64)
                {
                    return Err(bad_point(i / 4, v));
                }
                tets.par_extend(
                    conn.par_chunks_exact(4)
                        .map(|c| [c[0], c[1], c[2], c[3]].map(|v| (v as usize + base) as u32)),
                );
            } else {
                let mut start = 0usize;
                for (c, &end) in offsets.iter().enumerate() {
                    if end < start as i64 || end as u64 > conn.len() as u64 {
                        return Err(self.err_el(
                            off_el,
                            ErrorKind::IndexOutOfRange {
                                what: format!("offset of cell {c}"),
                                index: end.max(0) as u64,
                                limit: conn.len() as u64,
                            },
                        ));
                    }
                    start = end as usize;
                }
                let mut verts: Vec<u32> = Vec::with_capacity(10);
                for c in 0..nc {
                    verts.clear();
                    for &v in &conn[start_of(c)..offsets[c] as usize] {
                        if v < 0 || v as u64 >= np as u64 {
                            return Err(bad_point(c, v));
                        }
                        verts.push((v as usize + base) as u32);
                    }
                    let code = u32::try_from(types[c]).unwrap_or(u32::MAX);
                    crate::cells::cell_to_tets(code, &verts, &mut tets).map_err(|k| {
                        let k = match k {
                            ErrorKind::UnknownCellType(s) => {
                                ErrorKind::UnknownCellType(format!("{s} (cell {c})"))
                            }
                            k => k,
                        };
                        self.err_el(types_el, k)
                    })?;
                }
            }
            let src = self.choose_scalar(piece, options, np, nc)?;
            let (name, vals) = match src {
                ScalarSource::Point(n, v) => (n, v),
                ScalarSource::Cell(n, vals) => {
                    warnings.push(format!(
                        "no point data: cell array {n:?} averaged to the points"
                    ));
                    let mut sum = vec![0.0f64; np];
                    let mut cnt = vec![0u32; np];
                    for (c, &val) in vals.iter().enumerate() {
                        for &v in &conn[start_of(c)..offsets[c] as usize] {
                            sum[v as usize] += val;
                            cnt[v as usize] += 1;
                        }
                    }
                    (
                        n,
                        sum.iter()
                            .zip(&cnt)
                            .map(|(s, &c)| if c > 0 { s / c as f64 } else { 0.0 })
                            .collect(),
                    )
                }
                ScalarSource::None => {
                    warnings.push("no point or cell data: scalar set to 0".into());
                    ("zero".into(), vec![0.0; np])
                }
            };
            match &scalar_name {
                None => scalar_name = Some(name),
                Some(prev) if *prev != name => warnings.push(format!(
                    "pieces disagree on the scalar ({prev:?} vs {name:?})"
                )),
                _ => {}
            }
            scalars.extend(vals.iter().map(|&v| v as f32));
        }
        let mut mesh = TetMesh::new(
            self.mesh_name(),
            points,
            scalars,
            scalar_name.unwrap_or_default(),
            tets,
        )
        .map_err(|k| LoadError::new(self.path, k))?;
        mesh.repair.warnings.extend(warnings);
        Ok(Dataset {
            mesh,
            volume: None,
            source: self.path.display().to_string(),
        })
    }

    fn read_points(
        &self,
        el: &Element,
        np: usize,
        out: &mut Vec<[f32; 3]>,
    ) -> Result<(), LoadError> {
        let nc = self.components(el)?;
        if nc != 3 {
            return Err(self.err_el(
                el,
                ErrorKind::CountMismatch {
                    what: "components of Points".into(),
                    expected: 3,
                    found: nc as u64,
                },
            ));
        }
        let v = self.read_f64(el, np.saturating_mul(3))?;
        out.extend(
            v.chunks_exact(3)
                .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32]),
        );
        Ok(())
    }

    /// StructuredGrid and ImageData: pieces are sub-extents of `WholeExtent`, assembled into
    /// one grid, split by [`structured_tets`] (5 tets per cell, conforming).
    fn build_structured(
        &self,
        grid: &Element,
        image: bool,
        options: &LoadOptions,
    ) -> Result<Dataset, LoadError> {
        let whole: Vec<i64> = self.attr_numbers(grid, "WholeExtent", 6)?.ok_or_else(|| {
            self.err_el(
                grid,
                ErrorKind::Syntax {
                    expected: "a WholeExtent attribute".into(),
                    found: "nothing".into(),
                },
            )
        })?;
        let dims = self.extent_dims(grid, &whole)?;
        let npts = dims[0]
            .checked_mul(dims[1])
            .and_then(|d| d.checked_mul(dims[2]))
            .unwrap_or(usize::MAX);
        if npts > u32::MAX as usize {
            return Err(self.err_el(
                grid,
                ErrorKind::IndexOverflow {
                    what: "points".into(),
                    count: npts as u64,
                },
            ));
        }
        let cdims = dims.map(|d| d.saturating_sub(1).max(1));
        let ncells_whole = cdims.iter().product::<usize>();
        let (origin, spacing, direction) = if image {
            let o: Vec<f64> = self
                .attr_numbers(grid, "Origin", 3)?
                .unwrap_or_else(|| vec![0.0; 3]);
            let s: Vec<f64> = self
                .attr_numbers(grid, "Spacing", 3)?
                .unwrap_or_else(|| vec![1.0; 3]);
            let d: Vec<f64> = self
                .attr_numbers(grid, "Direction", 9)?
                .unwrap_or_else(|| vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
            ([o[0], o[1], o[2]], [s[0], s[1], s[2]], d)
        } else {
            ([0.0; 3], [1.0; 3], vec![])
        };
        let pieces: Vec<&Element> = grid.children_named("Piece").collect();
        if pieces.is_empty() {
            return Err(self.err_el(grid, ErrorKind::EmptyMesh(" (no <Piece>)".into())));
        }
        // Read every piece first (their arrays are checked against the data actually present),
        // then assemble: a WholeExtent the pieces cannot fill is an error, not an allocation.
        struct PieceData {
            off: [usize; 3],
            pdims: [usize; 3],
            pcdims: [usize; 3],
            points: Vec<[f32; 3]>,
            name: String,
            vals: Vec<f64>,
            is_point: bool,
        }
        let mut read = Vec::with_capacity(pieces.len());
        let mut covered = 0usize;
        for piece in pieces {
            let ext: Vec<i64> = self
                .attr_numbers(piece, "Extent", 6)?
                .unwrap_or_else(|| whole.clone());
            let pdims = self.extent_dims(piece, &ext)?;
            for a in 0..3 {
                if ext[2 * a] < whole[2 * a] || ext[2 * a + 1] > whole[2 * a + 1] {
                    return Err(self.err_el(
                        piece,
                        ErrorKind::Invalid(format!(
                            "piece Extent {ext:?} lies outside WholeExtent {whole:?}"
                        )),
                    ));
                }
            }
            // Inside the whole extent, so the products cannot overflow.
            let pn = pdims.iter().product::<usize>();
            let pcdims = pdims.map(|d| d.saturating_sub(1).max(1));
            let pcells = pcdims.iter().product::<usize>();
            let off = [0, 1, 2].map(|a| (ext[2 * a] - whole[2 * a]) as usize);
            let mut points = Vec::new();
            if !image {
                let pts_el = piece
                    .child("Points")
                    .and_then(|p| p.child("DataArray"))
                    .ok_or_else(|| {
                        self.err_el(
                            piece,
                            ErrorKind::Syntax {
                                expected: "<Points><DataArray …>".into(),
                                found: "none".into(),
                            },
                        )
                    })?;
                self.read_points(pts_el, pn, &mut points)?;
            }
            let (name, vals, is_point) = match self.choose_scalar(piece, options, pn, pcells)? {
                ScalarSource::Point(n, v) => (n, v, true),
                ScalarSource::Cell(n, v) => (n, v, false),
                ScalarSource::None if image => {
                    return Err(self.err_el(
                        piece,
                        ErrorKind::MissingArray {
                            name: "any point or cell array".into(),
                            available: vec![],
                        },
                    ))
                }
                ScalarSource::None => (String::new(), Vec::new(), true),
            };
            covered = covered.saturating_add(pn);
            read.push(PieceData {
                off,
                pdims,
                pcdims,
                points,
                name,
                vals,
                is_point,
            });
        }
        if covered < npts {
            return Err(self.err_el(
                grid,
                ErrorKind::CountMismatch {
                    what: "grid points given by the pieces (WholeExtent)".into(),
                    expected: npts as u64,
                    found: covered as u64,
                },
            ));
        }
        let (scalar_name, point_scalar) = (read[0].name.clone(), read[0].is_point);
        if read
            .iter()
            .any(|p| p.name != scalar_name || p.is_point != point_scalar)
        {
            return Err(self.err_el(
                grid,
                ErrorKind::Invalid(format!(
                    "pieces disagree on the scalar array ({scalar_name:?})"
                )),
            ));
        }
        let mut warnings = Vec::new();
        let mut points = vec![[0f32; 3]; if image { 0 } else { npts }];
        let mut scalars = vec![0f64; if point_scalar { npts } else { ncells_whole }];
        for p in read {
            let (off, pdims, pcdims) = (p.off, p.pdims, p.pcdims);
            // Global index of local point / cell (x fastest).
            let gp = |l: usize| {
                let (i, j, k) = (
                    l % pdims[0],
                    (l / pdims[0]) % pdims[1],
                    l / (pdims[0] * pdims[1]),
                );
                (i + off[0]) + dims[0] * ((j + off[1]) + dims[1] * (k + off[2]))
            };
            let gc = |l: usize| {
                let (i, j, k) = (
                    l % pcdims[0],
                    (l / pcdims[0]) % pcdims[1],
                    l / (pcdims[0] * pcdims[1]),
                );
                (i + off[0]) + cdims[0] * ((j + off[1]) + cdims[1] * (k + off[2]))
            };
            for (l, q) in p.points.into_iter().enumerate() {
                points[gp(l)] = q;
            }
            for (l, v) in p.vals.into_iter().enumerate() {
                scalars[if point_scalar { gp(l) } else { gc(l) }] = v;
            }
        }
        let scalar_name = if scalar_name.is_empty() {
            warnings.push("no point or cell data: scalar set to 0".into());
            "zero".to_string()
        } else {
            scalar_name
        };
        if !point_scalar {
            warnings.push(format!(
                "no point data: cell array {scalar_name:?} averaged to the points"
            ));
            scalars = cells_to_points(dims, &scalars);
        }
        let name = self.mesh_name();
        let values: Vec<f32> = scalars.iter().map(|&v| v as f32).collect();
        let identity =
            direction.is_empty() || direction == [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let (mut mesh, volume) = if image && identity {
            let vg = VoxelGrid {
                dims,
                spacing,
                origin: [0, 1, 2].map(|a| origin[a] + whole[2 * a] as f64 * spacing[a]),
                values,
                scalar_name: scalar_name.clone(),
            };
            let mut mesh = vg.to_tets().map_err(|k| LoadError::new(self.path, k))?;
            mesh.name = name;
            (mesh, Some(vg))
        } else {
            if image {
                warnings.push("ImageData with a non-identity Direction: converted to tets only (no voxel grid)".into());
                points = (0..npts)
                    .map(|g| {
                        let ijk = [
                            g % dims[0],
                            (g / dims[0]) % dims[1],
                            g / (dims[0] * dims[1]),
                        ];
                        let l =
                            [0, 1, 2].map(|a| (ijk[a] as f64 + whole[2 * a] as f64) * spacing[a]);
                        [0, 1, 2].map(|r| {
                            (origin[r]
                                + direction[3 * r] * l[0]
                                + direction[3 * r + 1] * l[1]
                                + direction[3 * r + 2] * l[2]) as f32
                        })
                    })
                    .collect();
            }
            let mesh = TetMesh::new(name, points, values, scalar_name, structured_tets(dims))
                .map_err(|k| LoadError::new(self.path, k))?;
            (mesh, None)
        };
        mesh.repair.warnings.extend(warnings);
        Ok(Dataset {
            mesh,
            volume,
            source: self.path.display().to_string(),
        })
    }

    fn extent_dims(&self, el: &Element, ext: &[i64]) -> Result<[usize; 3], LoadError> {
        let mut d = [0usize; 3];
        for a in 0..3 {
            let n = ext[2 * a + 1]
                .checked_sub(ext[2 * a])
                .and_then(|n| n.checked_add(1))
                .unwrap_or(0);
            if n < 1 {
                return Err(self.err_el(el, ErrorKind::Invalid(format!("empty extent {ext:?}"))));
            }
            d[a] = n as usize;
        }
        Ok(d)
    }
}

/// The default scalar among `arrays`: the holder's active `Scalars`, else the first
/// one-component array, else the first array.
fn pick_default(arrays: &[&Element], holder: Option<&Element>) -> Option<usize> {
    let active = holder.and_then(|h| h.attr("Scalars"));
    active
        .and_then(|a| arrays.iter().position(|e| e.attr("Name") == Some(a)))
        .or_else(|| {
            arrays
                .iter()
                .position(|e| e.attr("NumberOfComponents").is_none_or(|c| c.trim() == "1"))
        })
        .or(if arrays.is_empty() { None } else { Some(0) })
}

/// Averages cell values of a structured grid (cells x fastest) to its points.
fn cells_to_points(dims: [usize; 3], cells: &[f64]) -> Vec<f64> {
    let cd = dims.map(|d| d.saturating_sub(1).max(1));
    let n = dims.iter().product::<usize>();
    (0..n)
        .into_par_iter()
        .map(|g| {
            let ijk = [
                g % dims[0],
                (g / dims[0]) % dims[1],
                g / (dims[0] * dims[1]),
            ];
            let (mut s, mut c) = (0.0, 0u32);
            for dk in 0..2 {
                for dj in 0..2 {
                    for di in 0..2 {
                        let d = [di, dj, dk];
                        let mut cell = [0usize; 3];
                        let mut ok = true;
                        for a in 0..3 {
                            if ijk[a] < d[a] || ijk[a] - d[a] >= cd[a] {
                                ok = false;
                            } else {
                                cell[a] = ijk[a] - d[a];
                            }
                        }
                        if ok {
                            s += cells[cell[0] + cd[0] * (cell[1] + cd[1] * cell[2])];
                            c += 1;
                        }
                    }
                }
            }
            if c > 0 {
                s / c as f64
            } else {
                0.0
            }
        })
        .collect()
}

enum ScalarSource {
    Point(String, Vec<f64>),
    Cell(String, Vec<f64>),
    None,
}

enum Payload<'s> {
    Text(&'s [u8], u64),
    Bytes(Cow<'s, [u8]>, u64),
}

/// A byte stream an array block is read from.
trait Source<'s> {
    fn take(&mut self, n: usize, what: &str) -> Result<Cow<'s, [u8]>, ErrorKind>;
}

struct RawSource<'s> {
    data: &'s [u8],
    pos: usize,
    base: u64,
}

impl<'s> Source<'s> for RawSource<'s> {
    fn take(&mut self, n: usize, what: &str) -> Result<Cow<'s, [u8]>, ErrorKind> {
        let avail = self.data.len() - self.pos;
        if n > avail {
            return Err(ErrorKind::Truncated {
                expected: format!(
                    "{n} bytes of {what} at byte {}, only {avail} left",
                    self.base + self.pos as u64
                ),
            });
        }
        let s = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(Cow::Borrowed(s))
    }
}

/// Base64 text decoded on demand. VTK encodes the header and the data of compressed arrays as
/// separate base64 strings (each padded), so the text is decoded in runs that end at padding.
struct B64Source<'t> {
    text: &'t [u8],
    pos: usize,
    pending: Vec<u8>,
    base: u64,
}

const B64: base64::engine::GeneralPurpose = base64::engine::GeneralPurpose::new(
    &base64::alphabet::STANDARD,
    base64::engine::GeneralPurposeConfig::new()
        .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
);

impl<'s> Source<'s> for B64Source<'_> {
    fn take(&mut self, n: usize, what: &str) -> Result<Cow<'s, [u8]>, ErrorKind> {
        let max_avail = self.pending.len() + (self.text.len() - self.pos) / 4 * 3 + 3;
        if n > max_avail {
            return Err(ErrorKind::Truncated {
                expected: format!("{n} bytes of {what} in base64 text, at most {max_avail} left"),
            });
        }
        while self.pending.len() < n {
            if self.pos >= self.text.len() {
                return Err(ErrorKind::Truncated {
                    expected: format!("{n} bytes of {what} in base64 text"),
                });
            }
            let want = n - self.pending.len();
            let mut end = (self.pos + want.div_ceil(3) * 4).min(self.text.len());
            // Stop after the first padded group: what follows is a new base64 string.
            if let Some(eq) = self.text[self.pos..end].iter().position(|&b| b == b'=') {
                end = (self.pos + (eq / 4 + 1) * 4).min(self.text.len());
            }
            let chunk = &self.text[self.pos..end];
            B64.decode_vec(chunk, &mut self.pending).map_err(|e| {
                ErrorKind::Invalid(format!(
                    "bad base64 at character {} after byte {}: {e}",
                    self.pos, self.base
                ))
            })?;
            self.pos = end;
        }
        let rest = self.pending.split_off(n);
        let out = std::mem::replace(&mut self.pending, rest);
        Ok(Cow::Owned(out))
    }
}

/// Parses whitespace-separated numbers; on error returns the byte position and the fault.
fn parse_ascii<T: AsciiNum>(
    text: &[u8],
    pos: u64,
    float_ok: bool,
) -> Result<Vec<T>, (u64, ErrorKind)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < text.len() {
        while i < text.len() && text[i].is_ascii_whitespace() {
            i += 1;
        }
        let s = i;
        while i < text.len() && !text[i].is_ascii_whitespace() {
            i += 1;
        }
        if s == i {
            break;
        }
        let tok = std::str::from_utf8(&text[s..i]).unwrap_or("");
        match T::parse_tok(tok, float_ok) {
            Some(v) => out.push(v),
            None => {
                return Err((
                    pos + s as u64,
                    ErrorKind::Syntax {
                        expected: if float_ok {
                            "a number".into()
                        } else {
                            "an integer".into()
                        },
                        found: tok.chars().take(40).collect(),
                    },
                ))
            }
        }
    }
    Ok(out)
}

trait AsciiNum: Sized {
    fn parse_tok(tok: &str, float_ok: bool) -> Option<Self>;
}
impl AsciiNum for f64 {
    fn parse_tok(tok: &str, _: bool) -> Option<f64> {
        tok.parse().ok()
    }
}
impl AsciiNum for i64 {
    fn parse_tok(tok: &str, _: bool) -> Option<i64> {
        tok.parse().ok()
    }
}

macro_rules! conv {
    ($b:expr, $t:ty, $big:expr, $f:expr) => {{
        const N: usize = std::mem::size_of::<$t>();
        $b.par_chunks_exact(N)
            .map(|c| {
                let a: [u8; N] = c.try_into().unwrap();
                let v = if $big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                };
                $f(v)
            })
            .collect()
    }};
}

fn bytes_to_f64(b: &[u8], ty: NumType, big: bool) -> Vec<f64> {
    match ty {
        NumType::I8 => conv!(b, i8, big, |v| v as f64),
        NumType::U8 => conv!(b, u8, big, |v| v as f64),
        NumType::I16 => conv!(b, i16, big, |v| v as f64),
        NumType::U16 => conv!(b, u16, big, |v| v as f64),
        NumType::I32 => conv!(b, i32, big, |v| v as f64),
        NumType::U32 => conv!(b, u32, big, |v| v as f64),
        NumType::I64 => conv!(b, i64, big, |v| v as f64),
        NumType::U64 => conv!(b, u64, big, |v| v as f64),
        NumType::F32 => conv!(b, f32, big, |v| v as f64),
        NumType::F64 => conv!(b, f64, big, |v| v),
    }
}

/// Integer arrays as i64; a UInt64 value above i64::MAX gives (index, value).
fn bytes_to_i64(b: &[u8], ty: NumType, big: bool) -> Result<Vec<i64>, (usize, u64)> {
    Ok(match ty {
        NumType::I8 => conv!(b, i8, big, |v| v as i64),
        NumType::U8 => conv!(b, u8, big, |v| v as i64),
        NumType::I16 => conv!(b, i16, big, |v| v as i64),
        NumType::U16 => conv!(b, u16, big, |v| v as i64),
        NumType::I32 => conv!(b, i32, big, |v| v as i64),
        NumType::U32 => conv!(b, u32, big, |v| v as i64),
        NumType::I64 => conv!(b, i64, big, |v| v),
        NumType::U64 => {
            let v: Vec<u64> = conv!(b, u64, big, |v| v);
            if let Some(i) = v.iter().position(|&x| x > i64::MAX as u64) {
                return Err((i, v[i]));
            }
            v.into_iter().map(|x| x as i64).collect()
        }
        NumType::F32 | NumType::F64 => Vec::new(),
    })
}

fn line_of(bytes: &[u8], pos: u64) -> usize {
    let end = (pos as usize).min(bytes.len());
    bytes[..end].iter().filter(|&&b| b == b'\n').count() + 1
}

fn first_name(el: &Element) -> String {
    el.children
        .first()
        .map(|c| format!("<{}>", c.name))
        .unwrap_or_else(|| "nothing".into())
}

fn start_element(
    e: &BytesStart,
    pos: u64,
    path: &Path,
    reader_pos: u64,
) -> Result<Element, LoadError> {
    let name = String::from_utf8_lossy(e.name().as_ref()).into_owned();
    let mut attrs = Vec::new();
    for a in e.attributes() {
        let a = a.map_err(|err| {
            LoadError::at(
                path,
                Location::Byte(reader_pos),
                ErrorKind::Syntax {
                    expected: format!("well-formed attributes on <{name}>"),
                    found: err.to_string(),
                },
            )
        })?;
        let key = String::from_utf8_lossy(a.key.as_ref()).into_owned();
        let value = a.unescape_value().map_err(|err| {
            LoadError::at(
                path,
                Location::Byte(reader_pos),
                ErrorKind::Syntax {
                    expected: format!("a valid value of attribute {key}"),
                    found: err.to_string(),
                },
            )
        })?;
        attrs.push((key, value.into_owned()));
    }
    Ok(Element {
        name,
        attrs,
        children: Vec::new(),
        text: Vec::new(),
        pos,
        text_pos: pos,
    })
}

/// Builds the element tree. `cut` says the XML was cut at the `<AppendedData>` start tag, so
/// it and `<VTKFile>` are legitimately unclosed.
fn parse_tree(xml: &[u8], path: &Path, cut: bool) -> Result<Element, LoadError> {
    let mut reader = quick_xml::Reader::from_reader(xml);
    reader.config_mut().trim_text(false);
    let mut stack: Vec<Element> = vec![Element::default()];
    loop {
        let before = reader.buffer_position();
        let ev = reader.read_event();
        let after = reader.buffer_position();
        match ev {
            Ok(Event::Start(e)) => stack.push(start_element(&e, before, path, after)?),
            Ok(Event::Empty(e)) => {
                let el = start_element(&e, before, path, after)?;
                stack.last_mut().expect("root").children.push(el);
            }
            Ok(Event::End(_)) => {
                let el = stack.pop().expect("non-empty");
                match stack.last_mut() {
                    Some(parent) => parent.children.push(el),
                    None => {
                        return Err(LoadError::at(
                            path,
                            Location::Line(line_of(xml, before)),
                            ErrorKind::Syntax {
                                expected: "no closing tag without an opening one".into(),
                                found: String::new(),
                            },
                        ))
                    }
                }
            }
            Ok(Event::Text(t)) => {
                let top = stack.last_mut().expect("root");
                if top.text.is_empty() {
                    top.text_pos = after - t.len() as u64;
                }
                top.text.extend_from_slice(&t);
            }
            Ok(Event::CData(t)) => stack.last_mut().expect("root").text.extend_from_slice(&t),
            Ok(Event::Eof) => break,
            Ok(_) => {}
            Err(e) => {
                let at = reader.error_position();
                return Err(LoadError::at(
                    path,
                    Location::Line(line_of(xml, at)),
                    ErrorKind::Syntax {
                        expected: "well-formed XML".into(),
                        found: e.to_string(),
                    },
                ));
            }
        }
    }
    let open: Vec<String> = stack[1..].iter().map(|e| e.name.clone()).collect();
    let ok_open: &[&str] = if cut {
        &["VTKFile", "AppendedData"]
    } else {
        &[]
    };
    if open.iter().map(|s| s.as_str()).ne(ok_open.iter().copied()) {
        return Err(LoadError::at(
            path,
            Location::Byte(xml.len() as u64),
            ErrorKind::Truncated {
                expected: format!(
                    "closing tags for {}",
                    open.iter()
                        .map(|n| format!("<{n}>"))
                        .collect::<Vec<_>>()
                        .join(" ")
                ),
            },
        ));
    }
    while stack.len() > 1 {
        let el = stack.pop().expect("len > 1");
        stack.last_mut().expect("root").children.push(el);
    }
    Ok(stack.pop().expect("root"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::write_vtu::{vtu_bytes, VtuFormat, VtuOptions};

    fn data_file(name: &str) -> Option<std::path::PathBuf> {
        crate::registry::test_data_file(name)
    }

    fn parse(text: &str) -> Result<Dataset, LoadError> {
        from_bytes(
            text.as_bytes(),
            Path::new("test.vtu"),
            &LoadOptions::default(),
        )
    }

    fn kind(text: &str) -> ErrorKind {
        parse(text).expect_err("must fail").kind
    }

    #[test]
    fn reads_vtk_tetrahedron_vtu() {
        let Some(p) = data_file("Tetrahedron.vtu") else {
            return;
        };
        let ds = read(&p, &LoadOptions::default()).unwrap();
        assert_eq!((ds.mesh.num_points(), ds.mesh.num_tets()), (35, 96));
        assert_eq!(ds.mesh.scalar_name, "DistanceToCenter");
        let (lo, hi) = ds.mesh.scalar_range();
        assert!(
            lo.abs() < 1e-6 && (hi - 1.7320508).abs() < 1e-5,
            "{lo} {hi}"
        );
        let opts = LoadOptions {
            scalar: Some("Polynomial".into()),
            ..Default::default()
        };
        let ds = read(&p, &opts).unwrap();
        assert_eq!(ds.mesh.scalar_range(), (1.0, 7.0));
        let opts = LoadOptions {
            scalar: Some("Nope".into()),
            ..Default::default()
        };
        let err = read(&p, &opts).unwrap_err();
        assert!(
            matches!(&err.kind, ErrorKind::MissingArray { available, .. } if available.len() == 2),
            "{err}"
        );
    }

    fn all_layouts() -> Vec<VtuOptions> {
        let mut v = Vec::new();
        for format in [
            VtuFormat::Ascii,
            VtuFormat::Binary,
            VtuFormat::Appended,
            VtuFormat::AppendedBase64,
        ] {
            for compress in [false, true] {
                for header64 in [false, true] {
                    for big_endian in [false, true] {
                        if format == VtuFormat::Ascii && (compress || big_endian) {
                            continue;
                        }
                        v.push(VtuOptions {
                            format,
                            compress,
                            header64,
                            big_endian,
                        });
                    }
                }
            }
        }
        v
    }

    #[test]
    fn every_layout_reads_the_same_mesh() {
        let mut mesh = crate::generate::from_spec("slivers:3k:field=blobs", 5).unwrap();
        mesh.scalar_name = "a <strange> & \"quoted\" name".into();
        for o in all_layouts() {
            let bytes = vtu_bytes(&mesh, &o);
            let ds = from_bytes(&bytes, Path::new("x.vtu"), &LoadOptions::default())
                .unwrap_or_else(|e| panic!("{o:?}: {e}"));
            let m = &ds.mesh;
            assert_eq!(m.points, mesh.points, "{o:?}");
            assert_eq!(m.scalars, mesh.scalars, "{o:?}");
            assert_eq!(m.tets, mesh.tets, "{o:?}");
            assert_eq!(m.scalar_name, mesh.scalar_name, "{o:?}");
        }
    }

    /// Unit cube hexahedron 0..7, a pyramid on its top face (apex 8) and a wedge on its x=1
    /// face (points 9, 10): conforming splits leave exactly 2 triangles per quad on the boundary.
    const MIXED: &str = r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
 <UnstructuredGrid><Piece NumberOfPoints="11" NumberOfCells="3">
  <PointData><DataArray type="Float64" Name="x" format="ascii">0 1 1 0 0 1 1 0 0.5 2 2</DataArray></PointData>
  <Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">
   0 0 0  1 0 0  1 1 0  0 1 0  0 0 1  1 0 1  1 1 1  0 1 1  0.5 0.5 1.5  2 0 0.5  2 1 0.5
  </DataArray></Points>
  <Cells>
   <DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3 4 5 6 7  4 5 6 7 8  1 5 9 2 6 10</DataArray>
   <DataArray type="Int32" Name="offsets" format="ascii">8 13 19</DataArray>
   <DataArray type="UInt8" Name="types" format="ascii">12 14 13</DataArray>
  </Cells>
 </Piece></UnstructuredGrid>
</VTKFile>"#;

    #[test]
    fn hex_pyramid_wedge_split_conformingly() {
        let ds = parse(MIXED).unwrap();
        let m = &ds.mesh;
        // The hexahedron becomes 5 or 6 tets depending on its face diagonals.
        assert!(
            [5 + 2 + 3, 6 + 2 + 3].contains(&m.num_tets()),
            "{}",
            m.num_tets()
        );
        let vol: f64 = (0..m.num_tets())
            .map(|t| crate::mesh::signed_volume6(m.tet_points(t)) / 6.0)
            .sum();
        // Cube 1 + pyramid ⅓·1·½ + wedge ½·1 (triangle (1,0,0)(1,0,1)(2,0,.5) of area ½, length 1).
        assert!((vol - (1.0 + 1.0 / 6.0 + 0.5)).abs() < 1e-6, "{vol}");
        // Boundary: cube 4 free quads (8 tris) + pyramid 4 tris + wedge 2 tris + 2 quads (4 tris).
        assert_eq!(m.boundary_faces().len(), 8 + 4 + 2 + 4);
    }

    #[test]
    fn voxel_and_quadratic_tet_cells() {
        let voxel = MIXED
            .replace(
                "0 1 2 3 4 5 6 7  4 5 6 7 8  1 5 9 2 6 10",
                "0 1 3 2 4 5 7 6",
            )
            .replace("8 13 19", "8")
            .replace("12 14 13", "11")
            .replace("NumberOfCells=\"3\"", "NumberOfCells=\"1\"");
        let ds = parse(&voxel).unwrap();
        assert_eq!(ds.mesh.num_tets(), 6);
        assert_eq!(ds.mesh.repair.unused_points, 3);
        let vol: f64 = (0..6)
            .map(|t| crate::mesh::signed_volume6(ds.mesh.tet_points(t)) / 6.0)
            .sum();
        assert!((vol - 1.0).abs() < 1e-6);
        let quad = MIXED
            .replace(
                "0 1 2 3 4 5 6 7  4 5 6 7 8  1 5 9 2 6 10",
                "0 1 3 4 2 5 6 7 8 9",
            )
            .replace("8 13 19", "10")
            .replace("12 14 13", "24")
            .replace("NumberOfCells=\"3\"", "NumberOfCells=\"1\"");
        let ds = parse(&quad).unwrap();
        assert_eq!(ds.mesh.tets.len(), 1);
        let mut t = ds.mesh.tets[0];
        t.sort_unstable();
        assert_eq!(t, [0, 1, 3, 4]);
    }

    #[test]
    fn cell_data_only_is_averaged_with_a_warning() {
        let text = MIXED.replace(
            r#"<PointData><DataArray type="Float64" Name="x" format="ascii">0 1 1 0 0 1 1 0 0.5 2 2</DataArray></PointData>"#,
            r#"<CellData><DataArray type="Int16" Name="id" format="ascii">0 3 6</DataArray></CellData>"#,
        );
        let ds = parse(&text).unwrap();
        let m = &ds.mesh;
        assert_eq!(m.scalar_name, "id");
        assert!(m.repair.warnings.iter().any(|w| w.contains("averaged")));
        // Point 0: hex only → 0; point 8: pyramid only → 3; point 4 (hex, pyramid) → 1.5;
        // point 5 (all three) → 3; point 9 (wedge) → 6.
        assert_eq!(
            [
                m.scalars[0],
                m.scalars[8],
                m.scalars[4],
                m.scalars[5],
                m.scalars[9]
            ],
            [0.0, 3.0, 1.5, 3.0, 6.0]
        );
        let opts = LoadOptions {
            scalar: Some("x".into()),
            ..Default::default()
        };
        let err = from_bytes(text.as_bytes(), Path::new("t.vtu"), &opts).unwrap_err();
        assert!(
            matches!(&err.kind, ErrorKind::MissingArray { name, available } if name == "x" && available == &["id"])
        );
    }

    #[test]
    fn structured_grid_and_image_data() {
        // 3×2×2 points, two pieces splitting x (sharing the plane i = 1).
        let vts = r#"<VTKFile type="StructuredGrid" version="0.1">
<StructuredGrid WholeExtent="0 2 0 1 0 1">
<Piece Extent="0 1 0 1 0 1"><PointData Scalars="s"><DataArray type="Float32" Name="v" NumberOfComponents="3" format="ascii">0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0</DataArray><DataArray type="Float32" Name="s" format="ascii">0 1 0 1 0 1 0 1</DataArray></PointData>
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0 1 1 0 0 0 1 1 0 1 0 1 1 1 1 1</DataArray></Points></Piece>
<Piece Extent="1 2 0 1 0 1"><PointData Scalars="s"><DataArray type="Float32" Name="v" NumberOfComponents="3" format="ascii">0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0</DataArray><DataArray type="Float32" Name="s" format="ascii">1 2 1 2 1 2 1 2</DataArray></PointData>
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">1 0 0 2 0 0 1 1 0 2 1 0 1 0 1 2 0 1 1 1 1 2 1 1</DataArray></Points></Piece>
</StructuredGrid></VTKFile>"#;
        let ds = from_bytes(vts.as_bytes(), Path::new("g.vts"), &LoadOptions::default()).unwrap();
        assert_eq!((ds.mesh.num_points(), ds.mesh.num_tets()), (12, 10));
        assert_eq!(ds.mesh.scalar_name, "s");
        assert_eq!(ds.mesh.scalars[..3], [0.0, 1.0, 2.0]);
        assert_eq!(ds.mesh.points[2], [2.0, 0.0, 0.0]);
        // Boundary quads: 2·(2×1) on z faces, 2·(2×1) on y faces, 2·(1×1) on x faces.
        assert_eq!(ds.mesh.boundary_faces().len(), 2 * (4 + 4 + 2));
        assert!(ds.volume.is_none());

        let vti = r#"<VTKFile type="ImageData" version="0.1" byte_order="LittleEndian">
<ImageData WholeExtent="1 3 0 1 0 1" Origin="10 0 0" Spacing="0.5 1 2">
<Piece Extent="1 3 0 1 0 1"><CellData><DataArray type="UInt8" Name="c" format="ascii">4 8</DataArray></CellData></Piece>
</ImageData></VTKFile>"#;
        let ds = from_bytes(vti.as_bytes(), Path::new("v.vti"), &LoadOptions::default()).unwrap();
        let vg = ds.volume.as_ref().unwrap();
        assert_eq!(vg.dims, [3, 2, 2]);
        assert_eq!(vg.origin, [10.5, 0.0, 0.0]);
        assert_eq!(vg.values[..3], [4.0, 6.0, 8.0]);
        assert_eq!(ds.mesh.num_tets(), 10);
        assert_eq!(ds.mesh.points[1], [11.0, 0.0, 0.0]);
        assert!(ds
            .mesh
            .repair
            .warnings
            .iter()
            .any(|w| w.contains("averaged")));
    }

    fn binary_mesh() -> (TetMesh, VtuOptions) {
        let mesh = crate::generate::from_spec("box:1k:field=linear", 1).unwrap();
        (
            mesh,
            VtuOptions {
                format: VtuFormat::Binary,
                compress: false,
                header64: false,
                big_endian: false,
            },
        )
    }

    #[test]
    fn malformed_inputs_give_typed_errors() {
        let (mesh, o) = binary_mesh();
        let good = String::from_utf8(vtu_bytes(&mesh, &o)).unwrap();
        // Truncated base64: the Points array loses its second half.
        let start = good.find("Name=\"Points\"").unwrap();
        let text_start = good[start..].find('>').unwrap() + start + 2;
        let text_end = good[text_start..].find('\n').unwrap() + text_start;
        let cut = format!(
            "{}{}",
            &good[..text_start + (text_end - text_start) / 2],
            &good[text_end..]
        );
        assert!(
            matches!(kind(&cut), ErrorKind::Truncated { .. }),
            "{:?}",
            kind(&cut)
        );
        // Not base64.
        let bad = format!("{}!!!!{}", &good[..text_start], &good[text_start + 4..]);
        assert!(
            matches!(kind(&bad), ErrorKind::Invalid(_)),
            "{:?}",
            kind(&bad)
        );
        // Wrong counts.
        let n = mesh.num_points();
        let wrong = good.replace(
            &format!("NumberOfPoints=\"{n}\""),
            &format!("NumberOfPoints=\"{}\"", n - 1),
        );
        assert!(matches!(kind(&wrong), ErrorKind::CountMismatch { .. }));
        // Unknown cell type: a triangle (5) instead of tets.
        let mut ascii = String::from_utf8(vtu_bytes(
            &mesh,
            &VtuOptions {
                format: VtuFormat::Ascii,
                ..o
            },
        ))
        .unwrap();
        let ty = ascii.find("Name=\"types\"").unwrap();
        let ten = ascii[ty..].find("10").unwrap() + ty;
        ascii.replace_range(ten..ten + 2, " 5");
        let k = kind(&ascii);
        assert!(
            matches!(&k, ErrorKind::UnknownCellType(s) if s.contains("TRIANGLE") && s.contains("(cell 0)")),
            "{k:?}"
        );
        // Index out of range in the connectivity.
        let m = MIXED.replace("1 5 9 2 6 10", "1 5 9 2 6 11");
        assert!(matches!(
            kind(&m),
            ErrorKind::IndexOutOfRange {
                index: 11,
                limit: 11,
                ..
            }
        ));
        // Offsets that run backwards or past the connectivity.
        assert!(matches!(
            kind(&MIXED.replace("8 13 19", "8 7 19")),
            ErrorKind::IndexOutOfRange { .. }
        ));
        assert!(matches!(
            kind(&MIXED.replace("8 13 19", "8 13 20")),
            ErrorKind::IndexOutOfRange { .. }
        ));
        // Non-finite coordinate.
        assert!(matches!(
            kind(&MIXED.replace("0.5 0.5 1.5", "0.5 nan 1.5")),
            ErrorKind::NonFinite { .. }
        ));
        // Text where a number belongs.
        assert!(matches!(
            kind(&MIXED.replace("2 0 0.5", "2 zero 0.5")),
            ErrorKind::Syntax { .. }
        ));
        // Float connectivity.
        assert!(matches!(
            kind(&MIXED.replace(
                "type=\"Int32\" Name=\"connectivity\"",
                "type=\"Float32\" Name=\"connectivity\""
            )),
            ErrorKind::Syntax { .. }
        ));
        // Truncated XML.
        assert!(matches!(
            kind(&MIXED[..MIXED.len() / 2]),
            ErrorKind::Truncated { .. } | ErrorKind::Syntax { .. }
        ));
        // Not VTK at all / mismatched tags.
        assert!(matches!(kind("<html></html>"), ErrorKind::Syntax { .. }));
        assert!(matches!(
            kind(&MIXED.replace("</Points>", "</Pointz>")),
            ErrorKind::Syntax { .. }
        ));
        // Bad byte order, header type, compressor, dataset type.
        assert!(matches!(
            kind(&MIXED.replace("LittleEndian", "MiddleEndian")),
            ErrorKind::ByteOrder(_)
        ));
        assert!(matches!(
            kind(&MIXED.replace("version=\"0.1\"", "header_type=\"UInt16\"")),
            ErrorKind::Syntax { .. }
        ));
        assert!(matches!(
            kind(&good.replace(
                "header_type=",
                "compressor=\"vtkLZ4DataCompressor\" header_type="
            )),
            ErrorKind::Unsupported(_)
        ));
        assert!(matches!(
            kind(&MIXED.replace("\"UnstructuredGrid\"", "\"PolyData\"")),
            ErrorKind::Unsupported(_)
        ));
        // Empty mesh.
        let empty = r#"<VTKFile type="UnstructuredGrid"><UnstructuredGrid><Piece NumberOfPoints="0" NumberOfCells="0"><Points><DataArray type="Float32" NumberOfComponents="3" format="ascii"></DataArray></Points><Cells><DataArray type="Int32" Name="connectivity" format="ascii"></DataArray><DataArray type="Int32" Name="offsets" format="ascii"></DataArray><DataArray type="UInt8" Name="types" format="ascii"></DataArray></Cells></Piece></UnstructuredGrid></VTKFile>"#;
        assert!(matches!(kind(empty), ErrorKind::EmptyMesh(_)));
    }

    #[test]
    fn malformed_appended_and_compressed_data() {
        let (mesh, o) = binary_mesh();
        let raw = vtu_bytes(
            &mesh,
            &VtuOptions {
                format: VtuFormat::Appended,
                ..o
            },
        );
        let as_text = String::from_utf8_lossy(&raw).into_owned();
        let p = |b: &[u8]| {
            from_bytes(b, Path::new("a.vtu"), &LoadOptions::default())
                .expect_err("must fail")
                .kind
        };
        // File cut inside the appended block.
        assert!(matches!(
            p(&raw[..raw.len() - 200]),
            ErrorKind::Truncated { .. }
        ));
        // An offset beyond the appended data.
        let off = as_text.find("offset=\"0\"").unwrap();
        let mut bad = raw.clone();
        bad.splice(off..off + 10, b"offset=\"99999999\"".iter().copied());
        assert!(
            matches!(p(&bad), ErrorKind::IndexOutOfRange { .. }),
            "{:?}",
            p(&bad)
        );
        // Missing '_' marker.
        let us = find(&raw, b"encoding=\"raw\">\n   _").unwrap() + 19;
        assert_eq!(raw[us], b'_');
        let mut bad = raw.clone();
        bad[us] = b'X';
        assert!(matches!(p(&bad), ErrorKind::Syntax { .. }));
        // A block header announcing more bytes than exist.
        let mut bad = raw.clone();
        bad[us + 1..us + 5].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(p(&bad), ErrorKind::Truncated { .. }));
        // A byte count that is not a whole number of values.
        let mut bad = raw.clone();
        let n = u32::from_le_bytes(bad[us + 1..us + 5].try_into().unwrap());
        bad[us + 1..us + 5].copy_from_slice(&(n - 1).to_le_bytes());
        assert!(matches!(p(&bad), ErrorKind::Invalid(_)));
        // Corrupt zlib stream.
        let z = vtu_bytes(
            &mesh,
            &VtuOptions {
                format: VtuFormat::Appended,
                compress: true,
                ..o
            },
        );
        let us = find(&z, b"encoding=\"raw\">\n   _").unwrap() + 19;
        assert_eq!(z[us], b'_');
        let mut bad = z.clone();
        for b in &mut bad[us + 1 + 16 + 2..us + 1 + 16 + 12] {
            *b ^= 0x5A;
        }
        assert!(
            matches!(
                p(&bad),
                ErrorKind::Invalid(_) | ErrorKind::CountMismatch { .. }
            ),
            "{:?}",
            p(&bad)
        );
    }

    #[test]
    fn damaged_files_never_panic() {
        let (mesh, o) = binary_mesh();
        let mut inputs = Vec::new();
        for opts in [
            o,
            VtuOptions {
                compress: true,
                ..o
            },
            VtuOptions {
                format: VtuFormat::Appended,
                compress: true,
                ..o
            },
            VtuOptions {
                format: VtuFormat::Ascii,
                ..o
            },
        ] {
            inputs.push(vtu_bytes(&mesh, &opts));
        }
        // Deterministic damage: truncations and byte flips at many positions.
        let mut state = 0x1234_5678_9abc_def0u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for input in &inputs {
            for _ in 0..150 {
                let mut b = input.clone();
                match next() % 3 {
                    0 => b.truncate((next() as usize) % b.len()),
                    1 => {
                        let i = (next() as usize) % b.len();
                        b[i] = next() as u8;
                    }
                    _ => {
                        let i = (next() as usize) % b.len();
                        b[i] = b"<>\"_=0 9-"[(next() % 9) as usize];
                    }
                }
                let _ = from_bytes(&b, Path::new("fuzz.vtu"), &LoadOptions::default());
            }
        }
    }

    // Files written by VTK 9.7.2's XML writers (Python `vtk` wheel) from Tetrahedron.vtu and a
    // vtkRTAnalyticSource wavelet: cross-checks the reader against VTK's own layouts. They live
    // in datasets/testdata/vtk-written/ so that tests/vtkio_oracle.rs reads them too.
    const VTK_INLINE_ZLIB_U32: &str =
        include_str!("../testdata/vtk-written/tetrahedron-inline-zlib-u32.vtu");
    const VTK_APPENDED_BASE64_ZLIB_BIG: &str =
        include_str!("../testdata/vtk-written/tetrahedron-appended-base64-zlib-be.vtu");
    const VTK_VTS_INLINE_ZLIB_BIG: &str =
        include_str!("../testdata/vtk-written/wavelet-inline-zlib-be.vts");
    const VTK_VTI_RAW_ZLIB: &[u8] = include_bytes!("../testdata/vtk-written/wavelet-raw-zlib.vti");

    #[test]
    fn reads_files_written_by_vtk() {
        let p = |bytes: &[u8], name: &str| {
            from_bytes(bytes, Path::new(name), &LoadOptions::default())
                .unwrap_or_else(|e| panic!("{e}"))
        };
        let a = p(VTK_INLINE_ZLIB_U32.as_bytes(), "a.vtu");
        let b = p(VTK_APPENDED_BASE64_ZLIB_BIG.as_bytes(), "b.vtu");
        for m in [&a.mesh, &b.mesh] {
            assert_eq!((m.num_points(), m.num_tets()), (35, 96));
            assert_eq!(m.scalar_name, "DistanceToCenter");
            assert_eq!(m.boundary_faces().len(), 48);
        }
        assert_eq!(
            (&a.mesh.points, &a.mesh.scalars, &a.mesh.tets),
            (&b.mesh.points, &b.mesh.scalars, &b.mesh.tets)
        );
        if let Some(path) = data_file("Tetrahedron.vtu") {
            let o = read(&path, &LoadOptions::default()).unwrap();
            assert_eq!(
                (&a.mesh.points, &a.mesh.scalars, &a.mesh.tets),
                (&o.mesh.points, &o.mesh.scalars, &o.mesh.tets)
            );
        }
        let img = p(VTK_VTI_RAW_ZLIB, "w.vti");
        let vg = img.volume.as_ref().unwrap();
        assert_eq!(
            (vg.dims, vg.origin, vg.spacing),
            ([7, 5, 5], [-3.0, -2.0, 0.0], [1.0; 3])
        );
        assert_eq!(
            (
                img.mesh.num_points(),
                img.mesh.num_tets(),
                img.mesh.scalar_name.as_str()
            ),
            (175, 480, "RTData")
        );
        assert_eq!(img.mesh.scalar_range().1, 260.0);
        // The structured grid is the wavelet's points moved by (x + 0.1y, y, z + 0.05x²).
        let sg = p(VTK_VTS_INLINE_ZLIB_BIG.as_bytes(), "s.vts");
        assert_eq!(sg.mesh.scalars, img.mesh.scalars);
        assert_eq!(sg.mesh.tets, img.mesh.tets);
        for (q, r) in sg.mesh.points.iter().zip(&img.mesh.points) {
            let want = [r[0] + 0.1 * r[1], r[1], r[2] + 0.05 * r[0] * r[0]];
            assert!(
                (0..3).all(|k| (q[k] - want[k]).abs() < 1e-5),
                "{q:?} vs {want:?}"
            );
        }
    }
}
