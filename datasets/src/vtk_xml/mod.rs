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
//! no position (measurements in docs/dependencies.md).
//!
//! Non-tetrahedral cells are split into conforming tets by [`crate::cells::cell_to_tets`]
//! (shared with the legacy reader); cell data is averaged to the points when a file has no
//! point data (with a warning in the repair report).
//!
//! Layout: `xml` (the element tree, cutting off the appended block), `arrays` (DataArray
//! decoding: ascii, inline base64, zlib blocks, appended raw/base64), `pieces` (what every
//! dataset type shares: pieces, points, scalar choice, extents, the final mesh),
//! `unstructured` (cells split into tets) and `structured` (structured grids and images).

use std::path::Path;

use crate::dataset::{Dataset, LoadOptions};
use crate::error::{ErrorKind, LoadError, Location};

mod arrays;
mod pieces;
mod structured;
#[cfg(test)]
mod tests;
mod unstructured;
mod xml;

use arrays::Appended;
use xml::{first_name, line_of, Element};

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
}
