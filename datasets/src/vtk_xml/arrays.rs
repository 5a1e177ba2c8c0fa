//! DataArray decoding: element types, ASCII text, inline base64 (with or without
//! `vtkZLibDataCompressor` block headers) and the appended block (raw or base64), with
//! UInt32/UInt64 headers in either byte order.

use std::borrow::Cow;
use std::io::Read;

use base64::Engine;
use rayon::prelude::*;

use super::{Element, XmlFile};
use crate::error::{ErrorKind, LoadError, Location};

/// Where the appended block lives and how it is encoded.
pub(super) enum Appended<'a> {
    /// Raw bytes after the `_` marker, and their offset in the file.
    Raw(&'a [u8], u64),
    /// Base64 text after the `_` marker (without trailing whitespace), and its offset.
    Base64(&'a [u8], u64),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum NumType {
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
    pub(super) fn parse(s: &str) -> Option<NumType> {
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
    pub(super) fn size(self) -> usize {
        match self {
            NumType::I8 | NumType::U8 => 1,
            NumType::I16 | NumType::U16 => 2,
            NumType::I32 | NumType::U32 | NumType::F32 => 4,
            NumType::I64 | NumType::U64 | NumType::F64 => 8,
        }
    }
    pub(super) fn is_float(self) -> bool {
        matches!(self, NumType::F32 | NumType::F64)
    }
}

impl<'a> XmlFile<'a> {
    pub(super) fn array_type(&self, el: &Element) -> Result<NumType, LoadError> {
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

    pub(super) fn components(&self, el: &Element) -> Result<usize, LoadError> {
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
    pub(super) fn payload<'s>(&'s self, el: &'s Element) -> Result<Payload<'s>, LoadError> {
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

    pub(super) fn read_header_int<'s, S: Source<'s>>(&self, src: &mut S) -> Result<u64, ErrorKind> {
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
    pub(super) fn read_block<'s, S: Source<'s>>(
        &self,
        src: &mut S,
    ) -> Result<Cow<'s, [u8]>, ErrorKind> {
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
    pub(super) fn read_f64(&self, el: &Element, expected: usize) -> Result<Vec<f64>, LoadError> {
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
    pub(super) fn read_i64(
        &self,
        el: &Element,
        expected: Option<usize>,
    ) -> Result<Vec<i64>, LoadError> {
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

    pub(super) fn check_len<'b>(
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

    pub(super) fn check_count(
        &self,
        el: &Element,
        found: usize,
        expected: usize,
    ) -> Result<(), LoadError> {
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
}

pub(super) enum Payload<'s> {
    Text(&'s [u8], u64),
    Bytes(Cow<'s, [u8]>, u64),
}

/// A byte stream an array block is read from.
pub(super) trait Source<'s> {
    fn take(&mut self, n: usize, what: &str) -> Result<Cow<'s, [u8]>, ErrorKind>;
}

pub(super) struct RawSource<'s> {
    pub(super) data: &'s [u8],
    pub(super) pos: usize,
    pub(super) base: u64,
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
pub(super) struct B64Source<'t> {
    pub(super) text: &'t [u8],
    pub(super) pos: usize,
    pub(super) pending: Vec<u8>,
    pub(super) base: u64,
}

pub(super) const B64: base64::engine::GeneralPurpose = base64::engine::GeneralPurpose::new(
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
pub(super) fn parse_ascii<T: AsciiNum>(
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

pub(super) trait AsciiNum: Sized {
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

pub(super) fn bytes_to_f64(b: &[u8], ty: NumType, big: bool) -> Vec<f64> {
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
pub(super) fn bytes_to_i64(b: &[u8], ty: NumType, big: bool) -> Result<Vec<i64>, (usize, u64)> {
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
