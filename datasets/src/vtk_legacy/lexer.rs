//! Token-level reading of a legacy VTK file: the [`Parser`]'s position, keywords, counts and
//! reals, ASCII or big-endian binary value blocks checked against the bytes present, METADATA
//! skipped, and the errors located at a byte offset.

use std::path::Path;

use super::{DataType, Floats, TYPE_NAMES};
use crate::error::{ErrorKind, LoadError, Location};
use crate::read_util::{self as util, ByteOrder};

/// The reader's position in the file's bytes, with the token-level reads every section uses.
pub(super) struct Parser<'a> {
    pub(super) b: &'a [u8],
    pub(super) pos: usize,
    pub(super) binary: bool,
    pub(super) path: &'a Path,
}

fn is_ws(c: u8) -> bool {
    matches!(c, b' ' | b'\t' | b'\r' | b'\n' | 0x0b | 0x0c)
}

pub(super) fn show(tok: &[u8]) -> String {
    let s = String::from_utf8_lossy(&tok[..tok.len().min(40)]).into_owned();
    if tok.len() > 40 {
        format!("{s}…")
    } else {
        s
    }
}

impl<'a> Parser<'a> {
    pub(super) fn loc(&self, at: usize) -> Location {
        if self.binary {
            Location::Byte(at as u64)
        } else {
            util::line_of(self.b, at)
        }
    }
    pub(super) fn err(&self, at: usize, kind: ErrorKind) -> LoadError {
        LoadError::at(self.path, self.loc(at), kind)
    }
    pub(super) fn syntax(&self, at: usize, expected: impl Into<String>, found: &[u8]) -> LoadError {
        self.err(
            at,
            ErrorKind::Syntax {
                expected: expected.into(),
                found: show(found),
            },
        )
    }
    pub(super) fn truncated(&self, expected: impl Into<String>) -> LoadError {
        self.err(
            self.b.len(),
            ErrorKind::Truncated {
                expected: expected.into(),
            },
        )
    }

    pub(super) fn skip_ws(&mut self) {
        while self.pos < self.b.len() && is_ws(self.b[self.pos]) {
            self.pos += 1;
        }
    }
    /// Next whitespace-separated token and its start, or `None` at the end of the file.
    pub(super) fn token(&mut self) -> Option<(usize, &'a [u8])> {
        self.skip_ws();
        let start = self.pos;
        while self.pos < self.b.len() && !is_ws(self.b[self.pos]) {
            self.pos += 1;
        }
        (self.pos > start).then(|| (start, &self.b[start..self.pos]))
    }
    pub(super) fn peek_token(&self) -> Option<&'a [u8]> {
        let mut q = Parser {
            b: self.b,
            pos: self.pos,
            binary: self.binary,
            path: self.path,
        };
        q.token().map(|(_, t)| t)
    }
    pub(super) fn expect_token(&mut self, what: &str) -> Result<(usize, &'a [u8]), LoadError> {
        self.token().ok_or_else(|| self.truncated(what.to_string()))
    }
    pub(super) fn keyword(&mut self, kw: &str) -> Result<usize, LoadError> {
        let (at, t) = self.expect_token(kw)?;
        if t.eq_ignore_ascii_case(kw.as_bytes()) {
            Ok(at)
        } else {
            Err(self.syntax(at, format!("keyword {kw}"), t))
        }
    }
    pub(super) fn int(&mut self, what: &str) -> Result<(usize, i64), LoadError> {
        let (at, t) = self.expect_token(what)?;
        match std::str::from_utf8(t)
            .ok()
            .and_then(|s| s.parse::<i64>().ok())
        {
            Some(v) => Ok((at, v)),
            None => Err(self.syntax(at, what.to_string(), t)),
        }
    }
    /// A non-negative count.
    pub(super) fn count(&mut self, what: &str) -> Result<(usize, u64), LoadError> {
        let (at, v) = self.int(what)?;
        if v < 0 {
            return Err(self.syntax(
                at,
                format!("{what} (a non-negative count)"),
                v.to_string().as_bytes(),
            ));
        }
        Ok((at, v as u64))
    }
    pub(super) fn real(&mut self, what: &str) -> Result<(usize, f64), LoadError> {
        let (at, t) = self.expect_token(what)?;
        match std::str::from_utf8(t)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
        {
            Some(v) if v.is_finite() => Ok((at, v)),
            Some(v) => Err(self.err(
                at,
                ErrorKind::NonFinite {
                    what: what.to_string(),
                    index: 0,
                    value: v,
                },
            )),
            None => Err(self.syntax(at, what.to_string(), t)),
        }
    }
    pub(super) fn data_type(&mut self) -> Result<(usize, DataType), LoadError> {
        let (at, t) = self.expect_token("a data type")?;
        match DataType::parse(t) {
            Some(d) => Ok((at, d)),
            None if matches!(
                t.to_ascii_lowercase().as_slice(),
                b"bit" | b"string" | b"utf8_string" | b"variant"
            ) =>
            {
                Err(self.err(at, ErrorKind::Unsupported(format!("data type {}", show(t)))))
            }
            None => Err(self.syntax(at, TYPE_NAMES, t)),
        }
    }
    /// Whether another token follows on the current line.
    pub(super) fn more_on_line(&self) -> bool {
        let mut i = self.pos;
        while i < self.b.len() && matches!(self.b[i], b' ' | b'\t' | b'\r') {
            i += 1;
        }
        i < self.b.len() && self.b[i] != b'\n'
    }
    /// Moves past the end of the current line (binary data starts there).
    pub(super) fn next_line(&mut self) {
        while self.pos < self.b.len() && self.b[self.pos] != b'\n' {
            self.pos += 1;
        }
        self.pos = (self.pos + 1).min(self.b.len());
    }
    /// Returns the current line (without the newline) and moves past it.
    pub(super) fn line(&mut self) -> &'a [u8] {
        let start = self.pos;
        self.next_line();
        let end = if self.pos > start && self.b[self.pos - 1] == b'\n' {
            self.pos - 1
        } else {
            self.pos
        };
        &self.b[start..end]
    }

    /// Checks that `n` values can be present in the rest of the file before anything is
    /// allocated for them (a forged count must not trigger a huge allocation).
    pub(super) fn check_room(&self, n: u64, ty: DataType, what: &str) -> Result<usize, LoadError> {
        let left = (self.b.len() - self.pos) as u64;
        let need = if self.binary {
            n.checked_mul(ty.size() as u64)
        } else {
            n.checked_mul(2).map(|x| x.saturating_sub(1))
        };
        match need {
            Some(need) if need <= left => Ok(n as usize),
            _ => Err(self.truncated(format!(
                "{n} {} values for {what}{}, but only {left} bytes remain",
                if self.binary {
                    format!("{ty:?}")
                } else {
                    "ASCII".into()
                },
                if self.binary {
                    format!(" ({} bytes each)", ty.size())
                } else {
                    String::new()
                },
            ))),
        }
    }

    /// Reads `n` values as f32. Non-finite values are recorded (not rejected: only the arrays
    /// actually used must be finite).
    pub(super) fn floats(&mut self, n: u64, ty: DataType, what: &str) -> Result<Floats, LoadError> {
        if self.binary {
            self.next_line();
        }
        let n = self.check_room(n, ty, what)?;
        if self.binary {
            let start = self.pos;
            let raw = &self.b[start..start + n * ty.size()];
            self.pos += raw.len();
            let values: Vec<f32> = match ty {
                DataType::F32 => util::f32s(raw, ByteOrder::Big),
                DataType::F64 => util::f64s(raw, ByteOrder::Big)
                    .into_iter()
                    .map(|v| v as f32)
                    .collect(),
                _ => be_ints(raw, ty).into_iter().map(|v| v as f32).collect(),
            };
            let bad = values
                .iter()
                .position(|v| !v.is_finite())
                .map(|i| (i, start + i * ty.size(), values[i] as f64));
            Ok((values, bad))
        } else {
            let mut values = Vec::with_capacity(n);
            let mut bad = None;
            for i in 0..n {
                let (at, t) = self
                    .token()
                    .ok_or_else(|| self.truncated(format!("{n} values for {what}, found {i}")))?;
                let v = std::str::from_utf8(t).ok().and_then(|s| parse_real(s, ty));
                let Some(v) = v else {
                    return Err(self.syntax(at, format!("value {i} of {what} ({ty:?})"), t));
                };
                let f = v as f32;
                if bad.is_none() && !f.is_finite() {
                    bad = Some((i, at, v));
                }
                values.push(f);
            }
            Ok((values, bad))
        }
    }

    /// Reads `n` integer values (topology, cell types). Returns the values and where they start.
    pub(super) fn ints(
        &mut self,
        n: u64,
        ty: DataType,
        what: &str,
    ) -> Result<(Vec<i64>, usize), LoadError> {
        if ty.is_float() {
            return Err(self.err(
                self.pos,
                ErrorKind::Syntax {
                    expected: format!("an integer type for {what}"),
                    found: format!("{ty:?}"),
                },
            ));
        }
        if self.binary {
            self.next_line();
        }
        let n = self.check_room(n, ty, what)?;
        if self.binary {
            let start = self.pos;
            let raw = &self.b[start..start + n * ty.size()];
            self.pos += raw.len();
            Ok((be_ints(raw, ty), start))
        } else {
            let mut values = Vec::with_capacity(n);
            let start = self.pos;
            for i in 0..n {
                let (at, t) = self
                    .token()
                    .ok_or_else(|| self.truncated(format!("{n} integers for {what}, found {i}")))?;
                match std::str::from_utf8(t)
                    .ok()
                    .and_then(|s| s.parse::<i64>().ok())
                {
                    Some(v) => values.push(v),
                    None => return Err(self.syntax(at, format!("integer {i} of {what}"), t)),
                }
            }
            Ok((values, start))
        }
    }

    /// Byte offset of value `i` of a block starting at `start` (for located errors).
    pub(super) fn value_pos(&self, start: usize, i: usize, ty: DataType) -> usize {
        if self.binary {
            return start + i * ty.size();
        }
        let mut q = Parser {
            b: self.b,
            pos: start,
            binary: false,
            path: self.path,
        };
        let mut at = start;
        for _ in 0..=i {
            match q.token() {
                Some((a, _)) => at = a,
                None => break,
            }
        }
        at
    }

    /// Skips a METADATA block: lines up to an empty line (vtkDataReader does the same).
    pub(super) fn skip_metadata(&mut self) {
        self.next_line();
        while self.pos < self.b.len() {
            if self
                .line()
                .iter()
                .all(|&c| c == b' ' || c == b'\t' || c == b'\r')
            {
                break;
            }
        }
    }
    pub(super) fn skip_optional_metadata(&mut self) {
        if self
            .peek_token()
            .is_some_and(|t| t.eq_ignore_ascii_case(b"METADATA"))
        {
            self.token();
            self.skip_metadata();
        }
    }
}

pub(super) fn check_index_count(
    p: &Parser,
    at: usize,
    n: u64,
    what: &str,
) -> Result<(), LoadError> {
    if n > u32::MAX as u64 {
        return Err(p.err(
            at,
            ErrorKind::IndexOverflow {
                what: what.into(),
                count: n,
            },
        ));
    }
    Ok(())
}

pub(super) fn parse_real(s: &str, ty: DataType) -> Option<f64> {
    if ty.is_float() {
        s.parse::<f64>().ok()
    } else {
        s.parse::<i64>()
            .ok()
            .map(|v| v as f64)
            .or_else(|| s.parse::<f64>().ok().filter(|v| v.fract() == 0.0))
    }
}

/// Big-endian integers of any width, widened to i64 (u64 beyond i64 saturates).
pub(super) fn be_ints(raw: &[u8], ty: DataType) -> Vec<i64> {
    let n = ty.size();
    raw.chunks_exact(n)
        .map(|c| match ty {
            DataType::U8 => c[0] as i64,
            DataType::I8 => c[0] as i8 as i64,
            DataType::U16 => u16::from_be_bytes([c[0], c[1]]) as i64,
            DataType::I16 => i16::from_be_bytes([c[0], c[1]]) as i64,
            DataType::U32 => u32::from_be_bytes([c[0], c[1], c[2], c[3]]) as i64,
            DataType::I32 => i32::from_be_bytes([c[0], c[1], c[2], c[3]]) as i64,
            DataType::U64 => {
                u64::from_be_bytes(c.try_into().unwrap_or([0; 8])).min(i64::MAX as u64) as i64
            }
            DataType::I64 => i64::from_be_bytes(c.try_into().unwrap_or([0; 8])),
            DataType::F32 => f32::from_be_bytes([c[0], c[1], c[2], c[3]]) as i64,
            DataType::F64 => f64::from_be_bytes(c.try_into().unwrap_or([0; 8])) as i64,
        })
        .collect()
}

/// Whether `v` is out of range but its byte swap (at the width of `ty`) lies in `0..=limit`:
/// the signature of little-endian data in a file that must be big-endian.
pub(super) fn swapped_i64_plausible(v: i64, ty: DataType, limit: i64) -> bool {
    let s = match ty.size() {
        2 => (v as u16).swap_bytes() as i64,
        4 => (v as u32).swap_bytes() as i64,
        8 => v.swap_bytes(),
        _ => return false,
    };
    s != v && (0..=limit).contains(&s)
}

pub(super) fn byte_order_error(what: &str, v: i64) -> ErrorKind {
    ErrorKind::ByteOrder(format!(
        "{what} {v} is impossible but plausible byte-swapped: legacy VTK BINARY data must be big-endian and this looks little-endian"
    ))
}
