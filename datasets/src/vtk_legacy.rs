//! VTK legacy files (`.vtk`), ASCII and BINARY (big-endian), versions 1.0–4.2 and 5.1:
//! UNSTRUCTURED_GRID, STRUCTURED_GRID, STRUCTURED_POINTS, RECTILINEAR_GRID with POINT_DATA /
//! CELL_DATA attributes (SCALARS with LOOKUP_TABLE, FIELD arrays, and the other attribute kinds,
//! which are read and kept as arrays) and METADATA blocks (skipped).
//!
//! Why a hand-written parser instead of `vtkio`: vtkio 0.7.0-rc2 (the release with 5.1 support;
//! 0.6.3 fails on the OFFSETS/CONNECTIVITY layout) reports every parse failure as a bare
//! `nom::error::ErrorKind` — no line, no byte offset, no statement of what was expected — so it
//! cannot give the typed, located errors tetbench promises for bad input; its 5.1 cell reader
//! also accepts only `vtktypeint64` offsets. The format is small (keyword lines, then ASCII
//! tokens or packed big-endian values), so a direct reader is short, checks every count against
//! the bytes actually present before allocating, and converts binary blocks in bulk. vtkio is
//! kept as this reader's oracle (`tests/vtkio_oracle.rs`): it reads 11 of the 13 valid legacy
//! files the project has exactly as we do, and refuses `ironProt.vtk` (blank header lines) and
//! `unsigned_short` data.
//!
//! 5.1 layout: `CELLS n_offsets n_connectivity`, then `OFFSETS vtktypeint64` and
//! `CONNECTIVITY vtktypeint64` arrays; older versions use `CELLS n size` with `npts id…` per
//! cell. The layout is recognised from the content (an OFFSETS keyword), not the version line.

use std::path::Path;

use crate::cells;
use crate::dataset::{Dataset, LoadOptions};
use crate::error::{ErrorKind, LoadError, Location};
use crate::read_util::{self as util, ByteOrder};
use crate::volume::{structured_tets, VoxelGrid};
use crate::TetMesh;

/// Reads a legacy VTK file.
pub fn read(path: &Path, options: &LoadOptions) -> Result<Dataset, LoadError> {
    let bytes = util::read_file(path)?;
    from_bytes(&bytes, path, options)
}

/// Parses the content of a legacy VTK file; `path` only names it in errors and the mesh name.
/// Never panics on any input (fuzzed: `datasets/fuzz`).
pub fn from_bytes(bytes: &[u8], path: &Path, options: &LoadOptions) -> Result<Dataset, LoadError> {
    let mut p = Parser {
        b: bytes,
        pos: 0,
        binary: false,
        path,
    };
    let file = p.parse()?;
    file.build(&p, options)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum DataType {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    U64,
    I64,
    F32,
    F64,
}

impl DataType {
    fn parse(name: &[u8]) -> Option<DataType> {
        let n = name.to_ascii_lowercase();
        Some(match n.as_slice() {
            b"unsigned_char" | b"vtktypeuint8" => DataType::U8,
            b"char" | b"signed_char" | b"vtktypeint8" => DataType::I8,
            b"unsigned_short" | b"vtktypeuint16" => DataType::U16,
            b"short" | b"vtktypeint16" => DataType::I16,
            b"unsigned_int" | b"vtktypeuint32" => DataType::U32,
            // VTK writes vtkIdType arrays of legacy files as 32-bit ints (vtkDataReader).
            b"int" | b"vtktypeint32" | b"vtkidtype" => DataType::I32,
            b"unsigned_long" | b"unsigned_long_long" | b"vtktypeuint64" => DataType::U64,
            b"long" | b"long_long" | b"vtktypeint64" => DataType::I64,
            b"float" | b"vtktypefloat32" => DataType::F32,
            b"double" | b"vtktypefloat64" => DataType::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            DataType::U8 | DataType::I8 => 1,
            DataType::U16 | DataType::I16 => 2,
            DataType::U32 | DataType::I32 | DataType::F32 => 4,
            DataType::U64 | DataType::I64 | DataType::F64 => 8,
        }
    }
    fn is_float(self) -> bool {
        matches!(self, DataType::F32 | DataType::F64)
    }
}

const TYPE_NAMES: &str = "a data type (unsigned_char, char, unsigned_short, short, unsigned_int, int, unsigned_long, long, float, double, vtktypeint64, …)";

/// A numeric array read from the file (values converted to f32).
#[derive(Debug, Clone)]
struct Array {
    name: String,
    ncomp: usize,
    values: Vec<f32>,
    /// First non-finite value: (value index, byte offset of its token or bytes, value).
    non_finite: Option<(usize, usize, f64)>,
}

/// Values read as f32 and the first non-finite one (value index, byte offset, value).
type Floats = (Vec<f32>, Option<(usize, usize, f64)>);

/// Points, tets, cell count and (for STRUCTURED_POINTS) dims, origin and spacing.
type Geometry = (
    Vec<[f32; 3]>,
    Vec<[u32; 4]>,
    u64,
    Option<([usize; 3], [f64; 3], [f64; 3])>,
);

/// Which attribute block arrays currently go to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Target {
    Dataset,
    Point,
    Cell,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Unstructured,
    StructuredGrid,
    StructuredPoints,
    Rectilinear,
}

/// Cell connectivity as CSR, with where the values came from (for located errors).
#[derive(Debug, Default)]
struct Cells {
    offsets: Vec<usize>,
    conn: Vec<i64>,
    /// Start of the connectivity values and whether the legacy layout (counts interleaved).
    conn_at: usize,
    legacy_layout: bool,
    conn_type: Option<DataType>,
    at: usize,
}

#[derive(Debug, Default)]
struct VtkFile {
    kind: Option<Kind>,
    points: Option<(Vec<f32>, usize)>,
    cells: Option<Cells>,
    cell_types: Option<(Vec<i64>, usize, bool)>,
    dims: Option<([u64; 3], usize)>,
    origin: Option<[f64; 3]>,
    spacing: Option<[f64; 3]>,
    coords: [Option<(Vec<f32>, usize)>; 3],
    point_data: Option<(u64, usize)>,
    cell_data: Option<(u64, usize)>,
    point_arrays: Vec<Array>,
    cell_arrays: Vec<Array>,
}

struct Parser<'a> {
    b: &'a [u8],
    pos: usize,
    binary: bool,
    path: &'a Path,
}

fn is_ws(c: u8) -> bool {
    matches!(c, b' ' | b'\t' | b'\r' | b'\n' | 0x0b | 0x0c)
}

fn show(tok: &[u8]) -> String {
    let s = String::from_utf8_lossy(&tok[..tok.len().min(40)]).into_owned();
    if tok.len() > 40 {
        format!("{s}…")
    } else {
        s
    }
}

impl<'a> Parser<'a> {
    fn loc(&self, at: usize) -> Location {
        if self.binary {
            Location::Byte(at as u64)
        } else {
            util::line_of(self.b, at)
        }
    }
    fn err(&self, at: usize, kind: ErrorKind) -> LoadError {
        LoadError::at(self.path, self.loc(at), kind)
    }
    fn syntax(&self, at: usize, expected: impl Into<String>, found: &[u8]) -> LoadError {
        self.err(
            at,
            ErrorKind::Syntax {
                expected: expected.into(),
                found: show(found),
            },
        )
    }
    fn truncated(&self, expected: impl Into<String>) -> LoadError {
        self.err(
            self.b.len(),
            ErrorKind::Truncated {
                expected: expected.into(),
            },
        )
    }

    fn skip_ws(&mut self) {
        while self.pos < self.b.len() && is_ws(self.b[self.pos]) {
            self.pos += 1;
        }
    }
    /// Next whitespace-separated token and its start, or `None` at the end of the file.
    fn token(&mut self) -> Option<(usize, &'a [u8])> {
        self.skip_ws();
        let start = self.pos;
        while self.pos < self.b.len() && !is_ws(self.b[self.pos]) {
            self.pos += 1;
        }
        (self.pos > start).then(|| (start, &self.b[start..self.pos]))
    }
    fn peek_token(&self) -> Option<&'a [u8]> {
        let mut q = Parser {
            b: self.b,
            pos: self.pos,
            binary: self.binary,
            path: self.path,
        };
        q.token().map(|(_, t)| t)
    }
    fn expect_token(&mut self, what: &str) -> Result<(usize, &'a [u8]), LoadError> {
        self.token().ok_or_else(|| self.truncated(what.to_string()))
    }
    fn keyword(&mut self, kw: &str) -> Result<usize, LoadError> {
        let (at, t) = self.expect_token(kw)?;
        if t.eq_ignore_ascii_case(kw.as_bytes()) {
            Ok(at)
        } else {
            Err(self.syntax(at, format!("keyword {kw}"), t))
        }
    }
    fn int(&mut self, what: &str) -> Result<(usize, i64), LoadError> {
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
    fn count(&mut self, what: &str) -> Result<(usize, u64), LoadError> {
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
    fn real(&mut self, what: &str) -> Result<(usize, f64), LoadError> {
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
    fn data_type(&mut self) -> Result<(usize, DataType), LoadError> {
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
    fn more_on_line(&self) -> bool {
        let mut i = self.pos;
        while i < self.b.len() && matches!(self.b[i], b' ' | b'\t' | b'\r') {
            i += 1;
        }
        i < self.b.len() && self.b[i] != b'\n'
    }
    /// Moves past the end of the current line (binary data starts there).
    fn next_line(&mut self) {
        while self.pos < self.b.len() && self.b[self.pos] != b'\n' {
            self.pos += 1;
        }
        self.pos = (self.pos + 1).min(self.b.len());
    }
    /// Returns the current line (without the newline) and moves past it.
    fn line(&mut self) -> &'a [u8] {
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
    fn check_room(&self, n: u64, ty: DataType, what: &str) -> Result<usize, LoadError> {
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
    fn floats(&mut self, n: u64, ty: DataType, what: &str) -> Result<Floats, LoadError> {
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
    fn ints(&mut self, n: u64, ty: DataType, what: &str) -> Result<(Vec<i64>, usize), LoadError> {
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
    fn value_pos(&self, start: usize, i: usize, ty: DataType) -> usize {
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
    fn skip_metadata(&mut self) {
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
    fn skip_optional_metadata(&mut self) {
        if self
            .peek_token()
            .is_some_and(|t| t.eq_ignore_ascii_case(b"METADATA"))
        {
            self.token();
            self.skip_metadata();
        }
    }

    fn parse(&mut self) -> Result<VtkFile, LoadError> {
        // Header: "# vtk DataFile Version x.y", title line, ASCII|BINARY.
        let first = self.line();
        let first_s = String::from_utf8_lossy(first);
        let version = first_s
            .trim()
            .strip_prefix('#')
            .map(str::trim_start)
            .and_then(|s| {
                s.get(..12)
                    .filter(|p| p.eq_ignore_ascii_case("vtk DataFile"))
                    .map(|_| &s[12..])
            })
            .map(str::trim)
            .and_then(|s| {
                s.get(..7)
                    .filter(|p| p.eq_ignore_ascii_case("Version"))
                    .map(|_| s[7..].trim())
            });
        let Some(version) = version else {
            return Err(LoadError::at(
                self.path,
                Location::Line(1),
                ErrorKind::Syntax {
                    expected: "\"# vtk DataFile Version x.y\"".into(),
                    found: show(first),
                },
            ));
        };
        let v: Option<(u32, u32)> = version
            .split_once('.')
            .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)));
        match v {
            Some((1..=4, _)) | Some((5, 0..=1)) => {}
            Some(_) => {
                return Err(LoadError::at(
                    self.path,
                    Location::Line(1),
                    ErrorKind::Unsupported(format!(
                        "VTK legacy version {version} (1.0–5.1 are read)"
                    )),
                ))
            }
            None => {
                return Err(LoadError::at(
                    self.path,
                    Location::Line(1),
                    ErrorKind::Syntax {
                        expected: "a version number such as 4.2".into(),
                        found: version.to_string(),
                    },
                ))
            }
        }
        if self.pos >= self.b.len() {
            return Err(self.truncated("a title line"));
        }
        self.line(); // title
        let (at, fmt) = self.expect_token("ASCII or BINARY")?;
        if fmt.eq_ignore_ascii_case(b"BINARY") {
            self.binary = true;
        } else if !fmt.eq_ignore_ascii_case(b"ASCII") {
            return Err(self.syntax(at, "ASCII or BINARY", fmt));
        }

        let mut f = VtkFile::default();
        let mut target = Target::Dataset;
        while let Some((at, kw)) = self.token() {
            let k = kw.to_ascii_uppercase();
            match k.as_slice() {
                b"DATASET" => {
                    let (at2, t) = self.expect_token("a dataset type")?;
                    let kind = match t.to_ascii_uppercase().as_slice() {
                        b"UNSTRUCTURED_GRID" => Kind::Unstructured,
                        b"STRUCTURED_GRID" => Kind::StructuredGrid,
                        b"STRUCTURED_POINTS" => Kind::StructuredPoints,
                        b"RECTILINEAR_GRID" => Kind::Rectilinear,
                        b"POLYDATA" | b"FIELD" => {
                            return Err(self.err(at2, ErrorKind::Unsupported(format!("dataset {} has no volume cells", show(t)))))
                        }
                        _ => return Err(self.syntax(at2, "UNSTRUCTURED_GRID, STRUCTURED_GRID, STRUCTURED_POINTS or RECTILINEAR_GRID", t)),
                    };
                    if f.kind.is_some() {
                        return Err(self.syntax(at, "one DATASET", kw));
                    }
                    f.kind = Some(kind);
                }
                _ if f.kind.is_none() && k.as_slice() != b"FIELD" && k.as_slice() != b"METADATA" => {
                    return Err(self.syntax(at, "DATASET", kw));
                }
                b"POINTS" => {
                    self.require(&f, at, kw, &[Kind::Unstructured, Kind::StructuredGrid])?;
                    let (_, n) = self.count("the number of points")?;
                    check_index_count(self, at, n, "points")?;
                    let (_, ty) = self.data_type()?;
                    let (values, bad) = self.floats(n.saturating_mul(3), ty, "POINTS")?;
                    if let Some((i, pos, v)) = bad {
                        return Err(self.err(pos, ErrorKind::NonFinite { what: "coordinate of point".into(), index: (i / 3) as u64, value: v }));
                    }
                    self.skip_optional_metadata();
                    f.points = Some((values, at));
                }
                b"CELLS" => {
                    self.require(&f, at, kw, &[Kind::Unstructured])?;
                    f.cells = Some(self.cells(at)?);
                }
                b"CELL_TYPES" => {
                    self.require(&f, at, kw, &[Kind::Unstructured])?;
                    let (_, n) = self.count("the number of cell types")?;
                    let (types, start) = self.ints(n, DataType::I32, "CELL_TYPES")?;
                    f.cell_types = Some((types, start, self.binary));
                }
                b"DIMENSIONS" => {
                    self.require(&f, at, kw, &[Kind::StructuredGrid, Kind::StructuredPoints, Kind::Rectilinear])?;
                    let mut d = [0u64; 3];
                    for (a, v) in d.iter_mut().enumerate() {
                        let (at2, x) = self.count(["nx", "ny", "nz"][a])?;
                        if x == 0 {
                            return Err(self.syntax(at2, "a dimension of at least 1", b"0"));
                        }
                        *v = x;
                    }
                    f.dims = Some((d, at));
                }
                b"ORIGIN" | b"SPACING" | b"ASPECT_RATIO" => {
                    self.require(&f, at, kw, &[Kind::StructuredPoints])?;
                    let mut v = [0f64; 3];
                    for (a, x) in v.iter_mut().enumerate() {
                        *x = self.real(&format!("{} {}", show(kw), ["x", "y", "z"][a]))?.1;
                    }
                    if k.as_slice() == b"ORIGIN" {
                        f.origin = Some(v);
                    } else {
                        f.spacing = Some(v);
                    }
                }
                b"X_COORDINATES" | b"Y_COORDINATES" | b"Z_COORDINATES" => {
                    self.require(&f, at, kw, &[Kind::Rectilinear])?;
                    let axis = (k[0] - b'X') as usize;
                    let (_, n) = self.count("the number of coordinates")?;
                    let (_, ty) = self.data_type()?;
                    let (values, bad) = self.floats(n, ty, &show(kw))?;
                    if let Some((i, pos, v)) = bad {
                        return Err(self.err(pos, ErrorKind::NonFinite { what: format!("{} value", show(kw)), index: i as u64, value: v }));
                    }
                    self.skip_optional_metadata();
                    f.coords[axis] = Some((values, at));
                }
                b"POINT_DATA" => {
                    let (_, n) = self.count("the number of point values")?;
                    f.point_data = Some((n, at));
                    target = Target::Point;
                }
                b"CELL_DATA" => {
                    let (_, n) = self.count("the number of cell values")?;
                    f.cell_data = Some((n, at));
                    target = Target::Cell;
                }
                b"METADATA" => self.skip_metadata(),
                b"FIELD" => {
                    let (_, _name) = self.expect_token("a field name")?;
                    let (_, narrays) = self.count("the number of arrays")?;
                    let tuples = self.expected_tuples(&f, target);
                    for _ in 0..narrays {
                        let (at2, name) = self.expect_token("an array name")?;
                        if name.eq_ignore_ascii_case(b"NULL_ARRAY") {
                            continue;
                        }
                        let (_, ncomp) = self.count("the number of components")?;
                        let (at3, ntuples) = self.count("the number of tuples")?;
                        if let Some(t) = tuples {
                            if t != ntuples {
                                return Err(self.err(at3, ErrorKind::CountMismatch { what: format!("tuples of array {}", show(name)), expected: t, found: ntuples }));
                            }
                        }
                        let (_, ty) = self.data_type()?;
                        let arr = self.array(name, ncomp, ntuples, ty, at2)?;
                        self.skip_optional_metadata();
                        push_array(&mut f, target, arr);
                    }
                }
                b"SCALARS" | b"VECTORS" | b"NORMALS" | b"TENSORS" | b"TENSORS6" | b"TEXTURE_COORDINATES" | b"GLOBAL_IDS" | b"PEDIGREE_IDS" => {
                    if target == Target::Dataset {
                        return Err(self.syntax(at, "POINT_DATA or CELL_DATA before attribute arrays", kw));
                    }
                    let (_, name) = self.expect_token("an array name")?;
                    let (ncomp, ty) = match k.as_slice() {
                        b"TEXTURE_COORDINATES" => {
                            let (_, d) = self.count("the texture dimension")?;
                            (d, self.data_type()?.1)
                        }
                        _ => {
                            let ty = self.data_type()?.1;
                            let ncomp = match k.as_slice() {
                                b"SCALARS" if self.more_on_line() => self.count("the number of components")?.1,
                                b"SCALARS" | b"GLOBAL_IDS" | b"PEDIGREE_IDS" => 1,
                                b"TENSORS" => 9,
                                b"TENSORS6" => 6,
                                _ => 3,
                            };
                            (ncomp, ty)
                        }
                    };
                    if k.as_slice() == b"SCALARS" && self.peek_token().is_some_and(|t| t.eq_ignore_ascii_case(b"LOOKUP_TABLE")) {
                        self.token();
                        self.expect_token("a lookup table name")?;
                    }
                    let n = self.expected_tuples(&f, target).unwrap_or(0);
                    let arr = self.array(name, ncomp, n, ty, at)?;
                    self.skip_optional_metadata();
                    push_array(&mut f, target, arr);
                }
                b"COLOR_SCALARS" => {
                    let (_, name) = self.expect_token("an array name")?;
                    let (_, ncomp) = self.count("the number of colour components")?;
                    let n = self.expected_tuples(&f, target).unwrap_or(0);
                    // Binary colour scalars are unsigned chars, ASCII ones floats in [0, 1].
                    let ty = if self.binary { DataType::U8 } else { DataType::F32 };
                    let arr = self.array(name, ncomp, n, ty, at)?;
                    push_array(&mut f, target, arr);
                }
                b"LOOKUP_TABLE" => {
                    // A colour table (RGBA per entry): read past it.
                    self.expect_token("a lookup table name")?;
                    let (_, n) = self.count("the table size")?;
                    let ty = if self.binary { DataType::U8 } else { DataType::F32 };
                    self.floats(n.saturating_mul(4), ty, "LOOKUP_TABLE")?;
                }
                _ => {
                    return Err(self.syntax(
                        at,
                        "a section keyword (POINTS, CELLS, CELL_TYPES, DIMENSIONS, POINT_DATA, CELL_DATA, SCALARS, FIELD, …)",
                        kw,
                    ))
                }
            }
        }
        if f.kind.is_none() {
            return Err(self.truncated("DATASET"));
        }
        Ok(f)
    }

    fn require(&self, f: &VtkFile, at: usize, kw: &[u8], kinds: &[Kind]) -> Result<(), LoadError> {
        match f.kind {
            Some(k) if kinds.contains(&k) => Ok(()),
            k => Err(self.syntax(at, format!("a keyword of a {k:?} dataset"), kw)),
        }
    }

    fn expected_tuples(&self, f: &VtkFile, target: Target) -> Option<u64> {
        match target {
            Target::Point => f.point_data.map(|p| p.0),
            Target::Cell => f.cell_data.map(|c| c.0),
            Target::Dataset => None,
        }
    }

    fn array(
        &mut self,
        name: &[u8],
        ncomp: u64,
        ntuples: u64,
        ty: DataType,
        at: usize,
    ) -> Result<Array, LoadError> {
        if ncomp == 0 {
            return Err(self.syntax(at, "at least one component", b"0"));
        }
        let what = format!("array {}", show(name));
        let (values, non_finite) = self.floats(ncomp.saturating_mul(ntuples), ty, &what)?;
        Ok(Array {
            name: String::from_utf8_lossy(name).into_owned(),
            ncomp: ncomp as usize,
            values,
            non_finite,
        })
    }

    /// `CELLS` in either layout.
    fn cells(&mut self, at: usize) -> Result<Cells, LoadError> {
        let (_, a) = self.count("the number of cells")?;
        let (_, b) = self.count("the size of the cell list")?;
        if self
            .peek_token()
            .is_some_and(|t| t.eq_ignore_ascii_case(b"OFFSETS"))
        {
            // 5.1: CELLS n_offsets n_connectivity / OFFSETS type / CONNECTIVITY type.
            self.token();
            let (_, oty) = self.data_type()?;
            let (offsets, ostart) = self.ints(a, oty, "OFFSETS")?;
            self.skip_optional_metadata();
            self.keyword("CONNECTIVITY")?;
            let (_, cty) = self.data_type()?;
            let (conn, cstart) = self.ints(b, cty, "CONNECTIVITY")?;
            self.skip_optional_metadata();
            if offsets.is_empty() {
                return Err(self.err(
                    ostart,
                    ErrorKind::CountMismatch {
                        what: "OFFSETS entries (cells + 1)".into(),
                        expected: 1,
                        found: 0,
                    },
                ));
            }
            let mut offs = Vec::with_capacity(offsets.len());
            let mut prev = 0i64;
            for (i, &o) in offsets.iter().enumerate() {
                let bad = if i == 0 {
                    o != 0
                } else {
                    o < prev || o > b as i64
                };
                if bad {
                    if self.binary && (i > 0 || o != 0) && swapped_i64_plausible(o, oty, b as i64) {
                        return Err(self.err(
                            self.value_pos(ostart, i, oty),
                            byte_order_error("OFFSETS", o),
                        ));
                    }
                    return Err(self.err(
                        self.value_pos(ostart, i, oty),
                        ErrorKind::Invalid(format!("OFFSETS[{i}] = {o}: offsets must start at 0, never decrease and end at the CONNECTIVITY size {b}")),
                    ));
                }
                prev = o;
                offs.push(o as usize);
            }
            if prev != b as i64 {
                return Err(self.err(
                    ostart,
                    ErrorKind::CountMismatch {
                        what: "last OFFSETS entry vs CONNECTIVITY size".into(),
                        expected: b,
                        found: prev as u64,
                    },
                ));
            }
            Ok(Cells {
                offsets: offs,
                conn,
                conn_at: cstart,
                legacy_layout: false,
                conn_type: Some(cty),
                at,
            })
        } else {
            // ≤ 4.2: CELLS n size, then per cell: npts id id …
            let (list, start) = self.ints(b, DataType::I32, "CELLS")?;
            let mut offsets = Vec::with_capacity((a as usize).min(list.len() + 1));
            let mut conn = Vec::with_capacity(list.len().saturating_sub(a as usize));
            offsets.push(0);
            let mut k = 0usize;
            for c in 0..a {
                let Some(&npts) = list.get(k) else {
                    return Err(self.err(
                        start,
                        ErrorKind::CountMismatch {
                            what: format!("cells in a CELLS list of size {b}"),
                            expected: a,
                            found: c,
                        },
                    ));
                };
                if npts < 0 || (npts as u64) >= (list.len() - k) as u64 {
                    if self.binary && swapped_i64_plausible(npts, DataType::I32, 1000) {
                        return Err(self.err(
                            self.value_pos(start, k, DataType::I32),
                            byte_order_error("cell point count", npts),
                        ));
                    }
                    return Err(self.err(
                        self.value_pos(start, k, DataType::I32),
                        ErrorKind::Invalid(format!("cell {c} claims {npts} points but the CELLS list (size {b}) has {} values left", list.len() - k - 1)),
                    ));
                }
                conn.extend_from_slice(&list[k + 1..k + 1 + npts as usize]);
                k += 1 + npts as usize;
                offsets.push(conn.len());
            }
            if k != list.len() {
                return Err(self.err(
                    at,
                    ErrorKind::CountMismatch {
                        what: "CELLS list size".into(),
                        expected: b,
                        found: k as u64,
                    },
                ));
            }
            Ok(Cells {
                offsets,
                conn,
                conn_at: start,
                legacy_layout: true,
                conn_type: None,
                at,
            })
        }
    }
}

fn push_array(f: &mut VtkFile, target: Target, arr: Array) {
    match target {
        Target::Point => f.point_arrays.push(arr),
        Target::Cell => f.cell_arrays.push(arr),
        Target::Dataset => {} // dataset-level field data (time, cycle…): not a mesh scalar
    }
}

fn check_index_count(p: &Parser, at: usize, n: u64, what: &str) -> Result<(), LoadError> {
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

fn parse_real(s: &str, ty: DataType) -> Option<f64> {
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
fn be_ints(raw: &[u8], ty: DataType) -> Vec<i64> {
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
fn swapped_i64_plausible(v: i64, ty: DataType, limit: i64) -> bool {
    let s = match ty.size() {
        2 => (v as u16).swap_bytes() as i64,
        4 => (v as u32).swap_bytes() as i64,
        8 => v.swap_bytes(),
        _ => return false,
    };
    s != v && (0..=limit).contains(&s)
}

fn byte_order_error(what: &str, v: i64) -> ErrorKind {
    ErrorKind::ByteOrder(format!(
        "{what} {v} is impossible but plausible byte-swapped: legacy VTK BINARY data must be big-endian and this looks little-endian"
    ))
}

impl VtkFile {
    fn build(self, p: &Parser, options: &LoadOptions) -> Result<Dataset, LoadError> {
        let path = p.path;
        let kind = self.kind.unwrap_or(Kind::Unstructured);
        let end = p.b.len();
        // Geometry: points, tets and (for STRUCTURED_POINTS) the voxel grid parameters.
        let (points, tets, n_cells, regular): Geometry = match kind {
            Kind::Unstructured => {
                let (pts, _) = self.points.as_ref().ok_or_else(|| {
                    p.err(
                        end,
                        ErrorKind::Truncated {
                            expected: "a POINTS section".into(),
                        },
                    )
                })?;
                let points: Vec<[f32; 3]> =
                    pts.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
                let Some(cells) = self.cells.as_ref() else {
                    return Err(p.err(end, ErrorKind::EmptyMesh(" (no CELLS section)".into())));
                };
                let ncells = cells.offsets.len() - 1;
                let Some((types, tstart, _)) = self.cell_types.as_ref() else {
                    return Err(p.err(
                        end,
                        ErrorKind::Truncated {
                            expected: "a CELL_TYPES section".into(),
                        },
                    ));
                };
                if types.len() != ncells {
                    return Err(p.err(
                        *tstart,
                        ErrorKind::CountMismatch {
                            what: "CELL_TYPES entries vs CELLS".into(),
                            expected: ncells as u64,
                            found: types.len() as u64,
                        },
                    ));
                }
                let np = points.len() as i64;
                let conn_ty = cells.conn_type.unwrap_or(DataType::I32);
                // Index of value j of the connectivity within the file's value stream.
                let file_index = |j: usize| -> usize {
                    if cells.legacy_layout {
                        // Counts are interleaved: value j of cell c sits after c + 1 counts.
                        let c = cells.offsets.partition_point(|&o| o <= j);
                        j + c
                    } else {
                        j
                    }
                };
                let mut conn = Vec::with_capacity(cells.conn.len());
                for (j, &v) in cells.conn.iter().enumerate() {
                    if v < 0 || v >= np {
                        let at = p.value_pos(cells.conn_at, file_index(j), conn_ty);
                        if p.binary && swapped_i64_plausible(v, conn_ty, np - 1) {
                            return Err(p.err(at, byte_order_error("point index", v)));
                        }
                        if v < 0 {
                            return Err(p.err(
                                at,
                                ErrorKind::Syntax {
                                    expected: "a non-negative point index".into(),
                                    found: v.to_string(),
                                },
                            ));
                        }
                        return Err(p.err(
                            at,
                            ErrorKind::IndexOutOfRange {
                                what: "point".into(),
                                index: v as u64,
                                limit: np as u64,
                            },
                        ));
                    }
                    conn.push(v as u32);
                }
                let mut tets = Vec::with_capacity(ncells);
                for c in 0..ncells {
                    let t = types[c];
                    let ids = &conn[cells.offsets[c]..cells.offsets[c + 1]];
                    // Located only on error: finding an ASCII value's offset re-reads the block.
                    let at = || p.value_pos(*tstart, c, DataType::I32);
                    let t32 = u32::try_from(t).unwrap_or(u32::MAX);
                    if cells::vtk_cell_size(t32).is_none()
                        && p.binary
                        && swapped_i64_plausible(t, DataType::I32, 81)
                    {
                        return Err(p.err(at(), byte_order_error("cell type", t)));
                    }
                    cells::cell_to_tets(t32, ids, &mut tets).map_err(|k| {
                        let k = match k {
                            ErrorKind::UnknownCellType(s) if t32 == u32::MAX => {
                                ErrorKind::UnknownCellType(format!(
                                    "{t} (not a VTK cell type) {}",
                                    &s[s.find(';').unwrap_or(0)..]
                                ))
                            }
                            ErrorKind::CountMismatch {
                                what,
                                expected,
                                found,
                            } => ErrorKind::CountMismatch {
                                what: format!("{what} (cell {c})"),
                                expected,
                                found,
                            },
                            k => k,
                        };
                        p.err(at(), k)
                    })?;
                }
                if tets.len() > u32::MAX as usize {
                    return Err(p.err(
                        cells.at,
                        ErrorKind::IndexOverflow {
                            what: "tets".into(),
                            count: tets.len() as u64,
                        },
                    ));
                }
                (points, tets, ncells as u64, None)
            }
            Kind::StructuredGrid | Kind::StructuredPoints | Kind::Rectilinear => {
                let (dims, dat) = self.dims.ok_or_else(|| {
                    p.err(
                        end,
                        ErrorKind::Truncated {
                            expected: "a DIMENSIONS line".into(),
                        },
                    )
                })?;
                let n = util::grid_count(dims).map_err(|k| p.err(dat, k))?;
                let d = dims.map(|x| x as usize);
                let n_cells = d
                    .iter()
                    .map(|&x| x.saturating_sub(1) as u64)
                    .product::<u64>();
                if n_cells == 0 {
                    return Err(p.err(
                        dat,
                        ErrorKind::EmptyMesh(format!(
                            " (a {}×{}×{} grid has no 3-D cells)",
                            d[0], d[1], d[2]
                        )),
                    ));
                }
                let mut regular = None;
                let points = match kind {
                    Kind::StructuredGrid => {
                        let (pts, pat) = self.points.as_ref().ok_or_else(|| {
                            p.err(
                                end,
                                ErrorKind::Truncated {
                                    expected: "a POINTS section".into(),
                                },
                            )
                        })?;
                        if pts.len() / 3 != n {
                            return Err(p.err(
                                *pat,
                                ErrorKind::CountMismatch {
                                    what: "POINTS vs DIMENSIONS".into(),
                                    expected: n as u64,
                                    found: (pts.len() / 3) as u64,
                                },
                            ));
                        }
                        pts.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
                    }
                    _ => {
                        // Implicit points: their number is only backed by the file through its
                        // data arrays, so demand them before allocating (a tiny file must not
                        // conjure a 10⁹-point grid).
                        let backed = self
                            .point_data
                            .is_some_and(|(m, _)| m == n as u64 && !self.point_arrays.is_empty())
                            || self
                                .cell_data
                                .is_some_and(|(m, _)| m == n_cells && !self.cell_arrays.is_empty());
                        if !backed {
                            if let Some((m, pat)) = self.point_data.filter(|(m, _)| *m != n as u64)
                            {
                                return Err(p.err(
                                    pat,
                                    ErrorKind::CountMismatch {
                                        what: "POINT_DATA vs DIMENSIONS".into(),
                                        expected: n as u64,
                                        found: m,
                                    },
                                ));
                            }
                            return Err(p.err(
                                dat,
                                ErrorKind::MissingArray {
                                    name: "(point or cell data for the grid)".into(),
                                    available: vec![],
                                },
                            ));
                        }
                        if kind == Kind::StructuredPoints {
                            let origin = self.origin.unwrap_or([0.0; 3]);
                            let spacing = self.spacing.unwrap_or([1.0; 3]);
                            regular = Some((d, origin, spacing));
                            util::grid_points(d, origin, spacing)
                        } else {
                            let mut axes: Vec<&Vec<f32>> = Vec::with_capacity(3);
                            for a in 0..3 {
                                let (c, cat) = self.coords[a].as_ref().ok_or_else(|| {
                                    p.err(
                                        end,
                                        ErrorKind::Truncated {
                                            expected: format!("{}_COORDINATES", ["X", "Y", "Z"][a]),
                                        },
                                    )
                                })?;
                                if c.len() != d[a] {
                                    return Err(p.err(
                                        *cat,
                                        ErrorKind::CountMismatch {
                                            what: format!(
                                                "{}_COORDINATES vs DIMENSIONS",
                                                ["X", "Y", "Z"][a]
                                            ),
                                            expected: d[a] as u64,
                                            found: c.len() as u64,
                                        },
                                    ));
                                }
                                axes.push(c);
                            }
                            let mut pts = Vec::with_capacity(n);
                            for k in 0..d[2] {
                                for j in 0..d[1] {
                                    for i in 0..d[0] {
                                        pts.push([axes[0][i], axes[1][j], axes[2][k]]);
                                    }
                                }
                            }
                            pts
                        }
                    }
                };
                (points, structured_tets(d), n_cells, regular)
            }
        };

        // Attribute counts must match the geometry.
        if let Some((m, at)) = self.point_data {
            if m != points.len() as u64 {
                return Err(p.err(
                    at,
                    ErrorKind::CountMismatch {
                        what: "POINT_DATA values vs points".into(),
                        expected: points.len() as u64,
                        found: m,
                    },
                ));
            }
        }
        if let Some((m, at)) = self.cell_data {
            if m != n_cells {
                return Err(p.err(
                    at,
                    ErrorKind::CountMismatch {
                        what: "CELL_DATA values vs cells".into(),
                        expected: n_cells,
                        found: m,
                    },
                ));
            }
        }

        // The scalar: asked-for name, else first point array (1 component preferred), else a
        // cell array averaged to the points.
        let mut warnings = Vec::new();
        let chosen: Option<(&Array, bool)> = match &options.scalar {
            Some(name) => {
                let found = self
                    .point_arrays
                    .iter()
                    .find(|a| &a.name == name)
                    .map(|a| (a, false))
                    .or_else(|| {
                        self.cell_arrays
                            .iter()
                            .find(|a| &a.name == name)
                            .map(|a| (a, true))
                    });
                if found.is_none() {
                    let available = self
                        .point_arrays
                        .iter()
                        .chain(&self.cell_arrays)
                        .map(|a| a.name.clone())
                        .collect();
                    return Err(LoadError::new(
                        path,
                        ErrorKind::MissingArray {
                            name: name.clone(),
                            available,
                        },
                    ));
                }
                found
            }
            None => {
                fn pick(v: &[Array]) -> Option<&Array> {
                    v.iter().find(|a| a.ncomp == 1).or_else(|| v.first())
                }
                pick(&self.point_arrays)
                    .map(|a| (a, false))
                    .or_else(|| pick(&self.cell_arrays).map(|a| (a, true)))
            }
        };
        let (scalars, scalar_name) = match chosen {
            Some((arr, is_cell)) => {
                if let Some((i, pos, v)) = arr.non_finite {
                    let what = format!(
                        "value of array {} at {}",
                        arr.name,
                        if is_cell { "cell" } else { "point" }
                    );
                    return Err(p.err(
                        pos,
                        ErrorKind::NonFinite {
                            what,
                            index: (i / arr.ncomp) as u64,
                            value: v,
                        },
                    ));
                }
                let mut values = util::tuple_magnitudes(&arr.values, arr.ncomp);
                if arr.ncomp > 1 {
                    warnings.push(format!(
                        "array {} has {} components: its magnitude is the scalar",
                        arr.name, arr.ncomp
                    ));
                }
                if is_cell {
                    warnings.push(format!(
                        "cell data {} averaged to points (the file has no point array to use)",
                        arr.name
                    ));
                    values = match (&self.cells, kind) {
                        (Some(cells), Kind::Unstructured) => {
                            let conn: Vec<u32> = cells.conn.iter().map(|&v| v as u32).collect();
                            cells::cell_data_to_points(points.len(), &cells.offsets, &conn, &values)
                        }
                        _ => structured_cell_to_points(
                            regular
                                .map(|r| r.0)
                                .or(self.dims.map(|d| d.0.map(|x| x as usize)))
                                .unwrap_or([1; 3]),
                            &values,
                        ),
                    };
                }
                (values, arr.name.clone())
            }
            None => {
                warnings.push("no point or cell data: the scalar is 0 everywhere".to_string());
                (vec![0.0; points.len()], "none".to_string())
            }
        };

        let volume = regular.map(|(dims, origin, spacing)| {
            std::sync::Arc::new(VoxelGrid {
                dims,
                spacing,
                origin,
                values: scalars.clone().into(),
                scalar_name: scalar_name.clone(),
            })
        });
        let mut mesh = TetMesh::new(util::stem_name(path), points, scalars, scalar_name, tets)
            .map_err(|k| LoadError::new(path, k))?;
        mesh.repair.warnings.extend(warnings);
        Ok(Dataset {
            mesh,
            volume,
            source: path.display().to_string(),
        })
    }
}

/// Cell values of a structured grid (x fastest over cells) averaged to its points.
fn structured_cell_to_points(dims: [usize; 3], cell_values: &[f32]) -> Vec<f32> {
    let c = dims.map(|d| d.saturating_sub(1).max(1));
    let mut sum = vec![0f64; dims[0] * dims[1] * dims[2]];
    let mut cnt = vec![0u32; sum.len()];
    for k in 0..dims[2].saturating_sub(1) {
        for j in 0..dims[1].saturating_sub(1) {
            for i in 0..dims[0].saturating_sub(1) {
                let v = cell_values
                    .get(i + c[0] * (j + c[1] * k))
                    .copied()
                    .unwrap_or(0.0) as f64;
                for b in 0..8 {
                    let p =
                        (i + (b & 1)) + dims[0] * ((j + ((b >> 1) & 1)) + dims[1] * (k + (b >> 2)));
                    sum[p] += v;
                    cnt[p] += 1;
                }
            }
        }
    }
    sum.iter()
        .zip(&cnt)
        .map(|(&s, &n)| if n == 0 { 0.0 } else { (s / n as f64) as f32 })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &[u8]) -> Result<Dataset, LoadError> {
        from_bytes(text, Path::new("test.vtk"), &LoadOptions::default())
    }

    /// Two tets sharing a face, as ASCII legacy text of the given version and cell layout.
    fn two_tets_ascii(version: &str, modern: bool) -> String {
        let cells = if modern {
            "CELLS 3 8\nOFFSETS vtktypeint64\n0 4 8\nCONNECTIVITY vtktypeint64\n0 1 2 3\n1 2 3 4\n"
        } else {
            "CELLS 2 10\n4 0 1 2 3\n4 1 2 3 4\n"
        };
        format!(
            "# vtk DataFile Version {version}\ntwo tets\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n0 0 0 1 0 0 0 1 0\n0 0 1 1 1 1\n{cells}CELL_TYPES 2\n10\n10\nPOINT_DATA 5\nSCALARS temp float 1\nLOOKUP_TABLE default\n0 1 2 3 4\nFIELD FieldData 1\npressure 1 5 double\n5 6 7 8 9\n"
        )
    }

    fn be_f32(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_be_bytes()).collect()
    }
    fn be_i32(v: &[i32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_be_bytes()).collect()
    }
    fn be_i64(v: &[i64]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_be_bytes()).collect()
    }

    fn two_tets_binary(modern: bool) -> Vec<u8> {
        let mut b =
            b"# vtk DataFile Version 5.1\nbin\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n"
                .to_vec();
        b.extend(be_f32(&[
            0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 1., 1., 1.,
        ]));
        if modern {
            b.extend_from_slice(b"\nCELLS 3 8\nOFFSETS vtktypeint64\n");
            b.extend(be_i64(&[0, 4, 8]));
            b.extend_from_slice(b"\nCONNECTIVITY vtktypeint64\n");
            b.extend(be_i64(&[0, 1, 2, 3, 1, 2, 3, 4]));
        } else {
            b.extend_from_slice(b"\nCELLS 2 10\n");
            b.extend(be_i32(&[4, 0, 1, 2, 3, 4, 1, 2, 3, 4]));
        }
        b.extend_from_slice(b"\nCELL_TYPES 2\n");
        b.extend(be_i32(&[10, 10]));
        b.extend_from_slice(b"\nPOINT_DATA 5\nSCALARS temp double\nLOOKUP_TABLE default\n");
        b.extend([0f64, 1., 2., 3., 4.].iter().flat_map(|x| x.to_be_bytes()));
        b.extend_from_slice(b"\nMETADATA\nINFORMATION 0\n\n");
        b
    }

    fn check_two_tets(ds: &Dataset) {
        assert_eq!(ds.mesh.num_points(), 5);
        assert_eq!(ds.mesh.num_tets(), 2);
        assert_eq!(ds.mesh.scalar_name, "temp");
        assert_eq!(ds.mesh.scalars, vec![0., 1., 2., 3., 4.]);
        assert_eq!(ds.mesh.boundary_faces().len(), 6);
    }

    #[test]
    fn ascii_legacy_layouts() {
        for (v, modern) in [
            ("2.0", false),
            ("3.0", false),
            ("4.2", false),
            ("5.1", true),
        ] {
            let ds = parse(two_tets_ascii(v, modern).as_bytes()).unwrap();
            check_two_tets(&ds);
        }
        let opts = LoadOptions {
            scalar: Some("pressure".into()),
            ..Default::default()
        };
        let ds = from_bytes(
            two_tets_ascii("4.2", false).as_bytes(),
            Path::new("t.vtk"),
            &opts,
        )
        .unwrap();
        assert_eq!(ds.mesh.scalars, vec![5., 6., 7., 8., 9.]);
        let opts = LoadOptions {
            scalar: Some("nope".into()),
            ..Default::default()
        };
        let err = from_bytes(
            two_tets_ascii("4.2", false).as_bytes(),
            Path::new("t.vtk"),
            &opts,
        )
        .unwrap_err();
        assert!(
            matches!(&err.kind, ErrorKind::MissingArray { available, .. } if available == &["temp", "pressure"]),
            "{err}"
        );
    }

    #[test]
    fn binary_legacy_layouts() {
        check_two_tets(&parse(&two_tets_binary(false)).unwrap());
        check_two_tets(&parse(&two_tets_binary(true)).unwrap());
    }

    #[test]
    fn little_endian_binary_is_a_byte_order_error() {
        let good = two_tets_binary(false);
        // Re-encode the CELL_TYPES block little-endian.
        let key = b"CELL_TYPES 2\n";
        let at = good.windows(key.len()).position(|w| w == key).unwrap() + key.len();
        let mut bad = good.clone();
        bad[at..at + 8].copy_from_slice(&[10, 0, 0, 0, 10, 0, 0, 0]);
        let err = parse(&bad).unwrap_err();
        assert!(matches!(err.kind, ErrorKind::ByteOrder(_)), "{err}");
        assert_eq!(err.location, Some(Location::Byte(at as u64)));
    }

    #[test]
    fn structured_points_and_cell_data() {
        let text = b"# vtk DataFile Version 3.0\nv\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 3 2 2\nORIGIN 1 2 3\nSPACING 0.5 1 2\nCELL_DATA 2\nSCALARS c float\nLOOKUP_TABLE default\n1 3\n";
        let ds = parse(text).unwrap();
        let vol = ds.volume.as_ref().unwrap();
        assert_eq!(vol.dims, [3, 2, 2]);
        assert_eq!(ds.mesh.num_tets(), 10);
        assert_eq!(ds.mesh.points[11], [2.0, 3.0, 5.0]);
        // Middle column of points touches both cells: mean 2; the ends 1 and 3.
        assert_eq!(ds.mesh.scalars[0], 1.0);
        assert_eq!(ds.mesh.scalars[1], 2.0);
        assert_eq!(ds.mesh.scalars[2], 3.0);
        assert!(ds
            .mesh
            .repair
            .warnings
            .iter()
            .any(|w| w.contains("averaged")));
    }

    #[test]
    fn rectilinear_and_structured_grid() {
        let text = b"# vtk DataFile Version 4.2\nr\nASCII\nDATASET RECTILINEAR_GRID\nDIMENSIONS 2 2 3\nX_COORDINATES 2 float\n0 1\nY_COORDINATES 2 double\n0 2\nZ_COORDINATES 3 float\n0 1 3\nPOINT_DATA 12\nSCALARS s int 1\nLOOKUP_TABLE default\n0 1 2 3 4 5 6 7 8 9 10 11\n";
        let ds = parse(text).unwrap();
        assert_eq!(ds.mesh.num_tets(), 10);
        assert_eq!(ds.mesh.points[11], [1.0, 2.0, 3.0]);
        let text = b"# vtk DataFile Version 4.2\ns\nASCII\nDATASET STRUCTURED_GRID\nDIMENSIONS 2 2 2\nPOINTS 8 float\n0 0 0 1 0 0 0 1 0 1 1 0 0 0 1 1 0 1 0 1 1 1 1 1\nPOINT_DATA 8\nVECTORS v float\n1 0 0 0 3 4 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0\n";
        let ds = parse(text).unwrap();
        assert_eq!(ds.mesh.num_tets(), 5);
        assert_eq!(ds.mesh.scalars[1], 5.0);
    }

    #[test]
    fn mixed_cells_become_conforming_tets() {
        // A hexahedron, a wedge on top of it and a pyramid beside it.
        let text = b"# vtk DataFile Version 4.2\nmix\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 11 float\n0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1\n0.5 0 2 0.5 1 2\n2 0.5 0.5\nCELLS 3 22\n8 0 1 2 3 4 5 6 7\n6 4 5 8 7 6 9\n5 1 2 6 5 10\nCELL_TYPES 3\n12\n13\n14\n";
        let ds = parse(text).unwrap();
        assert_eq!(ds.mesh.num_tets(), 6 + 3 + 2);
        // Conforming: every internal face has two tets, so the boundary is the outer surface:
        // hex 4 free quads (8 tris) + wedge 2 tris + 2 quads (4 tris) + pyramid 4 tris.
        assert_eq!(ds.mesh.boundary_faces().len(), 8 + 2 + 4 + 4);
        let total: f64 = (0..ds.mesh.num_tets())
            .map(|t| crate::mesh::signed_volume6(ds.mesh.tet_points(t)) / 6.0)
            .sum();
        assert!((total - (1.0 + 0.5 + 1.0 / 3.0)).abs() < 1e-6, "{total}");
    }

    // The fuzz targets (datasets/fuzz) run for minutes; this is their quick stand-in that CI
    // runs every time: random bytes and random corruptions of valid files (ASCII and BINARY,
    // both cell layouts) give a mesh or a LoadError, never a panic.
    proptest::proptest! {
        #[test]
        fn random_bytes_never_panic(data in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..600)) {
            let mut with_header = b"# vtk DataFile Version 4.2\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\n".to_vec();
            with_header.extend_from_slice(&data);
            let _ = parse(&data);
            let _ = parse(&with_header);
        }

        #[test]
        fn corrupted_files_never_panic(which in 0usize..4, edits in proptest::collection::vec((proptest::prelude::any::<usize>(), proptest::prelude::any::<u8>()), 1..6)) {
            let mut b = match which {
                0 => two_tets_ascii("4.2", false).into_bytes(),
                1 => two_tets_ascii("5.1", true).into_bytes(),
                2 => two_tets_binary(false),
                _ => two_tets_binary(true),
            };
            for (at, v) in edits {
                let i = at % b.len();
                b[i] = v;
            }
            let _ = parse(&b);
        }
    }
}
