//! Loading any supported file into a [`Dataset`]: the format is chosen by sniffing the content
//! (magic strings, PLOT3D header ints consistent with the file size, TOFF count lines) and,
//! where the content is not distinctive, by the extension, then dispatched to the reader.
//!
//! The readers depend only on what they share ([`crate::dataset`], [`crate::cells`],
//! [`crate::read_util`]), never on this module; the re-exports below keep the older paths
//! (`datasets::load::cell_to_tets`, `datasets::load::ByteOrder`, …) working.

use std::io::Read;
use std::path::Path;

use crate::error::{ErrorKind, LoadError};
use crate::read_util::{io_error, trim_start};

pub use crate::cells::{
    cell_data_to_points, cell_to_tets, unknown_cell_type, vtk_cell_size, vtk_cell_type_name,
    VTK_HEXAHEDRON, VTK_PYRAMID, VTK_QUADRATIC_TETRA, VTK_TETRA, VTK_VOXEL, VTK_WEDGE,
};
pub use crate::dataset::{Dataset, LoadOptions, Plot3dField};
pub use crate::read_util::ByteOrder;

/// The file formats [`load`] knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    VtkLegacy,
    VtkXml,
    Plot3d,
    Toff,
    MetaImage,
}

/// Loads a mesh or volume from `path`, choosing the reader with [`detect_format`].
pub fn load(path: &Path, options: &LoadOptions) -> Result<Dataset, LoadError> {
    let mut ds = match detect_format(path)? {
        Format::VtkLegacy => crate::vtk_legacy::read(path, options),
        Format::VtkXml => crate::vtk_xml::read(path, options),
        Format::Plot3d => crate::plot3d::read(path, options),
        Format::Toff => crate::toff::read(path, options),
        Format::MetaImage => crate::mhd::read(path, options),
    }?;
    ds.source = path.display().to_string();
    ds.attach_grid();
    Ok(ds)
}

/// Chooses the reader for `path`: distinctive content first (`# vtk DataFile`, `<VTKFile`,
/// MetaImage keys), then the extension, then the weaker content tests (a PLOT3D header whose
/// grid size explains the file size; a TOFF file's two count lines).
pub fn detect_format(path: &Path) -> Result<Format, LoadError> {
    let mut file = std::fs::File::open(path).map_err(|e| io_error(path, &e))?;
    let len = file.metadata().map_err(|e| io_error(path, &e))?.len();
    let mut head = Vec::with_capacity(4096);
    file.by_ref()
        .take(4096)
        .read_to_end(&mut head)
        .map_err(|e| io_error(path, &e))?;
    if let Some(f) = sniff_magic(&head) {
        return Ok(f);
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("vtk") => return Ok(Format::VtkLegacy),
        Some("vtu" | "vts" | "vti") => return Ok(Format::VtkXml),
        Some("mhd" | "mha") => return Ok(Format::MetaImage),
        Some("toff" | "off" | "tet") => return Ok(Format::Toff),
        Some("bin" | "xyz" | "x" | "q" | "p3d" | "g" | "grd") => return Ok(Format::Plot3d),
        _ => {}
    }
    if crate::plot3d::sniff_xyz_header(&head, len) {
        return Ok(Format::Plot3d);
    }
    if crate::toff::sniff(&head) {
        return Ok(Format::Toff);
    }
    Err(LoadError::new(
        path,
        ErrorKind::UnknownFormat(
            "not VTK legacy, VTK XML, MetaImage, TOFF or PLOT3D (by content or by extension)"
                .into(),
        ),
    ))
}

/// Formats recognisable from their first bytes alone.
fn sniff_magic(head: &[u8]) -> Option<Format> {
    let trimmed = trim_start(head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(head));
    if trimmed.starts_with(b"# vtk DataFile") || trimmed.starts_with(b"# VTK DataFile") {
        return Some(Format::VtkLegacy);
    }
    if trimmed.starts_with(b"<?xml") || trimmed.starts_with(b"<VTKFile") {
        return Some(Format::VtkXml);
    }
    // MetaImage: "Key = Value" lines, one of the mandatory keys near the top.
    let first_keys = trimmed.split(|&c| c == b'\n').take(4);
    for line in first_keys {
        let l = trim_start(line);
        for key in [&b"ObjectType"[..], b"NDims"] {
            if let Some(rest) = l.strip_prefix(key) {
                if trim_start(rest).starts_with(b"=") {
                    return Some(Format::MetaImage);
                }
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sniffing_magic() {
        assert_eq!(
            sniff_magic(b"# vtk DataFile Version 3.0\n"),
            Some(Format::VtkLegacy)
        );
        assert_eq!(
            sniff_magic(b"<?xml version=\"1.0\"?>\n<VTKFile"),
            Some(Format::VtkXml)
        );
        assert_eq!(
            sniff_magic(b"ObjectType = Image\nNDims = 3\n"),
            Some(Format::MetaImage)
        );
        assert_eq!(sniff_magic(b"NDims = 3\n"), Some(Format::MetaImage));
        assert_eq!(sniff_magic(b"12\n4\n"), None);
    }
}
