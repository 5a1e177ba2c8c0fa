//! Piece assembly: choosing the scalar (point data, else cell data averaged to the points),
//! unstructured cells split into tets, structured grids and image data.

use rayon::prelude::*;

use super::{Element, XmlFile};
use crate::dataset::{Dataset, LoadOptions};
use crate::error::{ErrorKind, LoadError};
use crate::mesh::TetMesh;
use crate::volume::{structured_tets, VoxelGrid};

impl<'a> XmlFile<'a> {
    /// Chooses the point scalar: `options.scalar` by name, else the PointData's active
    /// `Scalars`, else its first one-component array, else its first array (as magnitude).
    /// Falls back to cell data (averaged by the caller) and finally to a zero field.
    pub(super) fn choose_scalar(
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
    pub(super) fn read_scalar_array(
        &self,
        el: &Element,
        tuples: usize,
    ) -> Result<Vec<f64>, LoadError> {
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

    pub(super) fn read_points(
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
    pub(super) fn build_structured(
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
                values: values.into(),
                scalar_name: scalar_name.clone(),
            };
            let mut mesh = vg.to_tets().map_err(|k| LoadError::new(self.path, k))?;
            mesh.name = name;
            (mesh, Some(std::sync::Arc::new(vg)))
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

    pub(super) fn extent_dims(&self, el: &Element, ext: &[i64]) -> Result<[usize; 3], LoadError> {
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
pub(super) fn pick_default(arrays: &[&Element], holder: Option<&Element>) -> Option<usize> {
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
pub(super) fn cells_to_points(dims: [usize; 3], cells: &[f64]) -> Vec<f64> {
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

pub(super) enum ScalarSource {
    Point(String, Vec<f64>),
    Cell(String, Vec<f64>),
    None,
}
