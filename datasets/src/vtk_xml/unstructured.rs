//! UnstructuredGrid: each piece's points, its cells split into tets (a fast path for files of
//! tets only), and its scalar (cell data averaged to the points), appended into one mesh.

use rayon::prelude::*;

use super::pieces::ScalarSource;
use super::{Element, XmlFile};
use crate::dataset::{Dataset, LoadOptions};
use crate::error::{ErrorKind, LoadError};

/// A piece's `<Cells>` arrays, decoded; `offsets` are cell *ends*.
struct Cells<'e> {
    conn_el: &'e Element,
    off_el: &'e Element,
    types_el: &'e Element,
    conn: Vec<i64>,
    offsets: Vec<i64>,
    types: Vec<i64>,
}

impl Cells<'_> {
    /// Cell `c`'s point ids: `conn[end(c − 1)..end(c)]` (the offsets checked first).
    fn points(&self, c: usize) -> &[i64] {
        let start = if c == 0 {
            0
        } else {
            self.offsets[c - 1] as usize
        };
        &self.conn[start..self.offsets[c] as usize]
    }
}

impl<'a> XmlFile<'a> {
    pub(super) fn build_unstructured(
        &self,
        grid: &Element,
        options: &LoadOptions,
    ) -> Result<Dataset, LoadError> {
        let mut points: Vec<[f32; 3]> = Vec::new();
        let mut scalars: Vec<f32> = Vec::new();
        let mut tets: Vec<[u32; 4]> = Vec::new();
        let mut warnings = Vec::new();
        let mut scalar_name: Option<String> = None;
        for piece in self.pieces(grid)? {
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
            self.piece_points(piece, np, &mut points)?;
            let cells = self.read_cells(piece, nc)?;
            self.cells_to_tets(&cells, np, base, &mut tets)?;
            let src = self.choose_scalar(piece, options, np, nc)?;
            let (name, vals) = point_values(src, &cells, np, &mut warnings);
            match &scalar_name {
                None => scalar_name = Some(name),
                Some(prev) if *prev != name => warnings.push(format!(
                    "pieces disagree on the scalar ({prev:?} vs {name:?})"
                )),
                _ => {}
            }
            scalars.extend(vals.iter().map(|&v| v as f32));
        }
        let mesh = self.tet_mesh(points, scalars, scalar_name.unwrap_or_default(), tets)?;
        Ok(self.dataset(mesh, None, warnings))
    }

    /// The piece's connectivity, offsets and types, the offsets checked against the
    /// connectivity (the `nc + 1` "starts" layout accepted too).
    fn read_cells<'e>(&self, piece: &'e Element, nc: usize) -> Result<Cells<'e>, LoadError> {
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
        let (conn_el, off_el, types_el) = (arr("connectivity")?, arr("offsets")?, arr("types")?);
        let conn = self.read_i64(conn_el, None)?;
        let mut offsets = self.read_i64(off_el, None)?;
        let types = self.read_i64(types_el, Some(nc))?;
        // Offsets are cell *ends* (nc values); accept the nc+1 "starts" layout too.
        if offsets.len() == nc + 1 && offsets.first() == Some(&0) {
            offsets.remove(0);
        }
        self.check_count(off_el, offsets.len(), nc)?;
        Ok(Cells {
            conn_el,
            off_el,
            types_el,
            conn,
            offsets,
            types,
        })
    }

    /// Appends the piece's cells to `tets` as conforming tets, point ids shifted by `base`.
    fn cells_to_tets(
        &self,
        cells: &Cells,
        np: usize,
        base: usize,
        tets: &mut Vec<[u32; 4]>,
    ) -> Result<(), LoadError> {
        let (conn, offsets, nc) = (&cells.conn, &cells.offsets, cells.types.len());
        let bad_point = |c: usize, v: i64| {
            self.err_el(
                cells.conn_el,
                ErrorKind::IndexOutOfRange {
                    what: format!("point of cell {c}"),
                    index: v.max(0) as u64,
                    limit: np as u64,
                },
            )
        };
        let pure_tets = conn.len() == 4 * nc
            && cells.types.par_iter().all(|&t| t == 10)
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
            return Ok(());
        }
        let mut start = 0usize;
        for (c, &end) in offsets.iter().enumerate() {
            if end < start as i64 || end as u64 > conn.len() as u64 {
                return Err(self.err_el(
                    cells.off_el,
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
            for &v in cells.points(c) {
                if v < 0 || v as u64 >= np as u64 {
                    return Err(bad_point(c, v));
                }
                verts.push((v as usize + base) as u32);
            }
            let code = u32::try_from(cells.types[c]).unwrap_or(u32::MAX);
            crate::cells::cell_to_tets(code, &verts, tets).map_err(|k| {
                let k = match k {
                    ErrorKind::UnknownCellType(s) => {
                        ErrorKind::UnknownCellType(format!("{s} (cell {c})"))
                    }
                    k => k,
                };
                self.err_el(cells.types_el, k)
            })?;
        }
        Ok(())
    }
}

/// The piece's scalar at its `np` points and its name: point data as read, cell data averaged
/// over the cells that hold each point, or zero (each fallback with a warning).
fn point_values(
    src: ScalarSource,
    cells: &Cells,
    np: usize,
    warnings: &mut Vec<String>,
) -> (String, Vec<f64>) {
    match src {
        ScalarSource::Point(n, v) => (n, v),
        ScalarSource::Cell(n, vals) => {
            warnings.push(format!(
                "no point data: cell array {n:?} averaged to the points"
            ));
            let mut sum = vec![0.0f64; np];
            let mut cnt = vec![0u32; np];
            for (c, &val) in vals.iter().enumerate() {
                for &v in cells.points(c) {
                    sum[v as usize] += val;
                    cnt[v as usize] += 1;
                }
            }
            let avg = sum
                .iter()
                .zip(&cnt)
                .map(|(s, &c)| if c > 0 { s / c as f64 } else { 0.0 })
                .collect();
            (n, avg)
        }
        ScalarSource::None => {
            warnings.push("no point or cell data: scalar set to 0".into());
            ("zero".into(), vec![0.0; np])
        }
    }
}
