//! The sections of a legacy VTK file into a [`VtkFile`]: the header, the dataset's geometry
//! keywords, the attribute blocks and their arrays, and `CELLS` in either layout.

use super::lexer::{byte_order_error, check_index_count, show, swapped_i64_plausible, Parser};
use super::{Array, Cells, DataType, Kind, Target, VtkFile};
use crate::error::{ErrorKind, LoadError, Location};

impl Parser<'_> {
    pub(super) fn parse(&mut self) -> Result<VtkFile, LoadError> {
        self.header()?;
        let mut f = VtkFile::default();
        let mut target = Target::Dataset;
        while let Some((at, kw)) = self.token() {
            let k = kw.to_ascii_uppercase();
            if k.as_slice() == b"DATASET" {
                let kind = self.dataset_kind()?;
                if f.kind.is_some() {
                    return Err(self.syntax(at, "one DATASET", kw));
                }
                f.kind = Some(kind);
            } else if f.kind.is_none() && k.as_slice() != b"FIELD" && k.as_slice() != b"METADATA" {
                return Err(self.syntax(at, "DATASET", kw));
            } else if !self.geometry_section(&mut f, at, kw, &k)?
                && !self.attribute_section(&mut f, &mut target, at, kw, &k)?
            {
                return Err(self.syntax(
                    at,
                    "a section keyword (POINTS, CELLS, CELL_TYPES, DIMENSIONS, POINT_DATA, CELL_DATA, SCALARS, FIELD, …)",
                    kw,
                ));
            }
        }
        if f.kind.is_none() {
            return Err(self.truncated("DATASET"));
        }
        Ok(f)
    }

    /// "# vtk DataFile Version x.y" (1.0–5.1), the title line, ASCII or BINARY.
    fn header(&mut self) -> Result<(), LoadError> {
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
        Ok(())
    }

    /// The type after `DATASET`: one of the four with volume cells.
    fn dataset_kind(&mut self) -> Result<Kind, LoadError> {
        let (at2, t) = self.expect_token("a dataset type")?;
        match t.to_ascii_uppercase().as_slice() {
            b"UNSTRUCTURED_GRID" => Ok(Kind::Unstructured),
            b"STRUCTURED_GRID" => Ok(Kind::StructuredGrid),
            b"STRUCTURED_POINTS" => Ok(Kind::StructuredPoints),
            b"RECTILINEAR_GRID" => Ok(Kind::Rectilinear),
            b"POLYDATA" | b"FIELD" => Err(self.err(
                at2,
                ErrorKind::Unsupported(format!("dataset {} has no volume cells", show(t))),
            )),
            _ => Err(self.syntax(
                at2,
                "UNSTRUCTURED_GRID, STRUCTURED_GRID, STRUCTURED_POINTS or RECTILINEAR_GRID",
                t,
            )),
        }
    }

    /// A keyword of the dataset's geometry (`k` is `kw` in capitals); false for any other.
    fn geometry_section(
        &mut self,
        f: &mut VtkFile,
        at: usize,
        kw: &[u8],
        k: &[u8],
    ) -> Result<bool, LoadError> {
        match k {
            b"POINTS" => {
                self.require(f, at, kw, &[Kind::Unstructured, Kind::StructuredGrid])?;
                let (_, n) = self.count("the number of points")?;
                check_index_count(self, at, n, "points")?;
                let (_, ty) = self.data_type()?;
                let (values, bad) = self.floats(n.saturating_mul(3), ty, "POINTS")?;
                if let Some((i, pos, v)) = bad {
                    return Err(self.err(
                        pos,
                        ErrorKind::NonFinite {
                            what: "coordinate of point".into(),
                            index: (i / 3) as u64,
                            value: v,
                        },
                    ));
                }
                self.skip_optional_metadata();
                f.points = Some((values, at));
            }
            b"CELLS" => {
                self.require(f, at, kw, &[Kind::Unstructured])?;
                f.cells = Some(self.cells(at)?);
            }
            b"CELL_TYPES" => {
                self.require(f, at, kw, &[Kind::Unstructured])?;
                let (_, n) = self.count("the number of cell types")?;
                let (types, start) = self.ints(n, DataType::I32, "CELL_TYPES")?;
                f.cell_types = Some((types, start, self.binary));
            }
            b"DIMENSIONS" => {
                self.require(
                    f,
                    at,
                    kw,
                    &[
                        Kind::StructuredGrid,
                        Kind::StructuredPoints,
                        Kind::Rectilinear,
                    ],
                )?;
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
                self.require(f, at, kw, &[Kind::StructuredPoints])?;
                let mut v = [0f64; 3];
                for (a, x) in v.iter_mut().enumerate() {
                    *x = self
                        .real(&format!("{} {}", show(kw), ["x", "y", "z"][a]))?
                        .1;
                }
                if k == b"ORIGIN" {
                    f.origin = Some(v);
                } else {
                    f.spacing = Some(v);
                }
            }
            b"X_COORDINATES" | b"Y_COORDINATES" | b"Z_COORDINATES" => {
                self.require(f, at, kw, &[Kind::Rectilinear])?;
                let axis = (k[0] - b'X') as usize;
                let (_, n) = self.count("the number of coordinates")?;
                let (_, ty) = self.data_type()?;
                let (values, bad) = self.floats(n, ty, &show(kw))?;
                if let Some((i, pos, v)) = bad {
                    return Err(self.err(
                        pos,
                        ErrorKind::NonFinite {
                            what: format!("{} value", show(kw)),
                            index: i as u64,
                            value: v,
                        },
                    ));
                }
                self.skip_optional_metadata();
                f.coords[axis] = Some((values, at));
            }
            _ => return Ok(false),
        }
        Ok(true)
    }

    /// A keyword of the attribute blocks (`k` is `kw` in capitals); false for any other.
    fn attribute_section(
        &mut self,
        f: &mut VtkFile,
        target: &mut Target,
        at: usize,
        kw: &[u8],
        k: &[u8],
    ) -> Result<bool, LoadError> {
        match k {
            b"POINT_DATA" => {
                let (_, n) = self.count("the number of point values")?;
                f.point_data = Some((n, at));
                *target = Target::Point;
            }
            b"CELL_DATA" => {
                let (_, n) = self.count("the number of cell values")?;
                f.cell_data = Some((n, at));
                *target = Target::Cell;
            }
            b"METADATA" => self.skip_metadata(),
            b"FIELD" => {
                let (_, _name) = self.expect_token("a field name")?;
                let (_, narrays) = self.count("the number of arrays")?;
                let tuples = self.expected_tuples(f, *target);
                for _ in 0..narrays {
                    let (at2, name) = self.expect_token("an array name")?;
                    if name.eq_ignore_ascii_case(b"NULL_ARRAY") {
                        continue;
                    }
                    let (_, ncomp) = self.count("the number of components")?;
                    let (at3, ntuples) = self.count("the number of tuples")?;
                    if let Some(t) = tuples {
                        if t != ntuples {
                            return Err(self.err(
                                at3,
                                ErrorKind::CountMismatch {
                                    what: format!("tuples of array {}", show(name)),
                                    expected: t,
                                    found: ntuples,
                                },
                            ));
                        }
                    }
                    let (_, ty) = self.data_type()?;
                    let arr = self.array(name, ncomp, ntuples, ty, at2)?;
                    self.skip_optional_metadata();
                    push_array(f, *target, arr);
                }
            }
            b"SCALARS"
            | b"VECTORS"
            | b"NORMALS"
            | b"TENSORS"
            | b"TENSORS6"
            | b"TEXTURE_COORDINATES"
            | b"GLOBAL_IDS"
            | b"PEDIGREE_IDS" => {
                if *target == Target::Dataset {
                    return Err(self.syntax(
                        at,
                        "POINT_DATA or CELL_DATA before attribute arrays",
                        kw,
                    ));
                }
                let (_, name) = self.expect_token("an array name")?;
                let (ncomp, ty) = match k {
                    b"TEXTURE_COORDINATES" => {
                        let (_, d) = self.count("the texture dimension")?;
                        (d, self.data_type()?.1)
                    }
                    _ => {
                        let ty = self.data_type()?.1;
                        let ncomp = match k {
                            b"SCALARS" if self.more_on_line() => {
                                self.count("the number of components")?.1
                            }
                            b"SCALARS" | b"GLOBAL_IDS" | b"PEDIGREE_IDS" => 1,
                            b"TENSORS" => 9,
                            b"TENSORS6" => 6,
                            _ => 3,
                        };
                        (ncomp, ty)
                    }
                };
                if k == b"SCALARS"
                    && self
                        .peek_token()
                        .is_some_and(|t| t.eq_ignore_ascii_case(b"LOOKUP_TABLE"))
                {
                    self.token();
                    self.expect_token("a lookup table name")?;
                }
                let n = self.expected_tuples(f, *target).unwrap_or(0);
                let arr = self.array(name, ncomp, n, ty, at)?;
                self.skip_optional_metadata();
                push_array(f, *target, arr);
            }
            b"COLOR_SCALARS" => {
                let (_, name) = self.expect_token("an array name")?;
                let (_, ncomp) = self.count("the number of colour components")?;
                let n = self.expected_tuples(f, *target).unwrap_or(0);
                // Binary colour scalars are unsigned chars, ASCII ones floats in [0, 1].
                let ty = if self.binary {
                    DataType::U8
                } else {
                    DataType::F32
                };
                let arr = self.array(name, ncomp, n, ty, at)?;
                push_array(f, *target, arr);
            }
            b"LOOKUP_TABLE" => {
                // A colour table (RGBA per entry): read past it.
                self.expect_token("a lookup table name")?;
                let (_, n) = self.count("the table size")?;
                let ty = if self.binary {
                    DataType::U8
                } else {
                    DataType::F32
                };
                self.floats(n.saturating_mul(4), ty, "LOOKUP_TABLE")?;
            }
            _ => return Ok(false),
        }
        Ok(true)
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
