//! Writes any [`TetMesh`] as a VTK XML UnstructuredGrid (`.vtu`) so ParaView users can open it.
//!
//! The default layout is what ParaView itself writes: raw appended data, UInt64 block headers,
//! little-endian, Float32 points and scalar — the f32 values are stored bit for bit, so reading
//! the file back ([`crate::vtk_xml`]) gives the identical mesh. The other layouts (ascii,
//! inline base64, appended base64, zlib-compressed, big-endian, UInt32 headers) exist so the
//! reader can be tested against every variant VTK produces.
//!
//! vtkio could write `.vtu` too, and VTK reads its output back exactly, but for Blunt Fin its
//! file is 2.4× larger (UInt64 cells, base64 only) and 6–26× slower to write
//! (docs/dependencies.md; `datasets/examples/vtkio_measure.rs`), so this writer stays.

use std::io::Write;
use std::path::Path;

use base64::Engine;
use rayon::prelude::*;

use crate::error::{ErrorKind, LoadError};
use crate::TetMesh;

/// How DataArrays are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VtuFormat {
    /// Numbers as text (f32 printed in the shortest form that reads back exactly).
    Ascii,
    /// Base64 inside each DataArray.
    Binary,
    /// Raw bytes in one `<AppendedData encoding="raw">` block.
    Appended,
    /// Base64 text in one `<AppendedData encoding="base64">` block.
    AppendedBase64,
}

/// Layout options for [`write_vtu_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VtuOptions {
    pub format: VtuFormat,
    /// zlib-compress binary data (vtkZLibDataCompressor, 32 KiB blocks).
    pub compress: bool,
    /// UInt64 block headers (VTK ≥ 6 default) instead of UInt32.
    pub header64: bool,
    pub big_endian: bool,
}

impl Default for VtuOptions {
    fn default() -> Self {
        VtuOptions {
            format: VtuFormat::Appended,
            compress: false,
            header64: true,
            big_endian: false,
        }
    }
}

/// VTK's default compression block size.
const BLOCK_SIZE: usize = 32768;

/// Writes `mesh` to `path` as raw-appended `.vtu`.
pub fn write_vtu(mesh: &TetMesh, path: &Path) -> Result<(), LoadError> {
    write_vtu_with(mesh, path, &VtuOptions::default())
}

/// Writes `mesh` to `path` in the given layout.
pub fn write_vtu_with(mesh: &TetMesh, path: &Path, options: &VtuOptions) -> Result<(), LoadError> {
    let io = |e: std::io::Error| LoadError::new(path, ErrorKind::Io(e.to_string()));
    let file = std::fs::File::create(path).map_err(io)?;
    let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
    write_to(mesh, &mut w, options).map_err(io)?;
    w.flush().map_err(io)
}

/// The `.vtu` content in memory (tests, small meshes).
pub fn vtu_bytes(mesh: &TetMesh, options: &VtuOptions) -> Vec<u8> {
    let mut out = Vec::new();
    write_to(mesh, &mut out, options).expect("writing to a Vec cannot fail");
    out
}

/// Element type of an array, as written.
#[derive(Clone, Copy)]
enum Ty {
    F32,
    I32,
    I64,
    U8,
}

impl Ty {
    fn name(self) -> &'static str {
        match self {
            Ty::F32 => "Float32",
            Ty::I32 => "Int32",
            Ty::I64 => "Int64",
            Ty::U8 => "UInt8",
        }
    }
}

/// One array to write: name, components, element type and its values.
struct Array<'m> {
    name: String,
    components: usize,
    ty: Ty,
    values: Values<'m>,
}

enum Values<'m> {
    Points(&'m [[f32; 3]]),
    Scalars(&'m [f32]),
    Conn(&'m [[u32; 4]]),
    Offsets(usize),
    Types(usize),
}

impl Array<'_> {
    fn len(&self) -> usize {
        match &self.values {
            Values::Points(p) => 3 * p.len(),
            Values::Scalars(s) => s.len(),
            Values::Conn(t) => 4 * t.len(),
            Values::Offsets(n) | Values::Types(n) => *n,
        }
    }

    /// Element `i` as text.
    fn text(&self, i: usize) -> String {
        match &self.values {
            Values::Points(p) => format!("{}", p[i / 3][i % 3]),
            Values::Scalars(s) => format!("{}", s[i]),
            Values::Conn(t) => format!("{}", t[i / 4][i % 4]),
            Values::Offsets(_) => format!("{}", 4 * (i + 1)),
            Values::Types(_) => "10".into(),
        }
    }

    /// All elements as bytes in the requested byte order.
    fn bytes(&self, big: bool) -> Vec<u8> {
        macro_rules! enc {
            ($iter:expr, $n:expr) => {{
                let mut out = Vec::with_capacity($n);
                for v in $iter {
                    out.extend_from_slice(&if big {
                        v.to_be_bytes()
                    } else {
                        v.to_le_bytes()
                    });
                }
                out
            }};
        }
        let n = self.len();
        match (&self.values, self.ty) {
            (Values::Points(p), _) => enc!(p.iter().flatten(), 4 * n),
            (Values::Scalars(s), _) => enc!(s.iter(), 4 * n),
            (Values::Conn(t), Ty::I32) => enc!(t.iter().flatten().map(|&v| v as i32), 4 * n),
            (Values::Conn(t), _) => enc!(t.iter().flatten().map(|&v| v as i64), 8 * n),
            (Values::Offsets(c), Ty::I32) => enc!((1..=*c).map(|i| (4 * i) as i32), 4 * n),
            (Values::Offsets(c), _) => enc!((1..=*c).map(|i| (4 * i) as i64), 8 * n),
            (Values::Types(c), _) => vec![10u8; *c],
        }
    }
}

fn header_int(v: u64, o: &VtuOptions, out: &mut Vec<u8>) {
    match (o.header64, o.big_endian) {
        (true, false) => out.extend_from_slice(&v.to_le_bytes()),
        (true, true) => out.extend_from_slice(&v.to_be_bytes()),
        (false, false) => out.extend_from_slice(&(v as u32).to_le_bytes()),
        (false, true) => out.extend_from_slice(&(v as u32).to_be_bytes()),
    }
}

/// The binary block of an array: (header, data). Uncompressed: header = byte count.
/// Compressed: header = [#blocks, block size, last block size, compressed sizes…].
fn binary_block(data: &[u8], o: &VtuOptions) -> (Vec<u8>, Vec<u8>) {
    let mut header = Vec::new();
    if !o.compress {
        header_int(data.len() as u64, o, &mut header);
        return (header, data.to_vec());
    }
    let blocks: Vec<Vec<u8>> = data
        .par_chunks(BLOCK_SIZE)
        .map(|c| {
            let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            e.write_all(c).expect("in-memory");
            e.finish().expect("in-memory")
        })
        .collect();
    header_int(blocks.len() as u64, o, &mut header);
    header_int(BLOCK_SIZE as u64, o, &mut header);
    header_int((data.len() % BLOCK_SIZE) as u64, o, &mut header);
    for b in &blocks {
        header_int(b.len() as u64, o, &mut header);
    }
    (header, blocks.concat())
}

/// Base64 of a block. Like VTK, the header of a compressed block is a separate base64 string
/// (so it can be decoded before the data); uncompressed blocks are encoded in one piece, as
/// VTK's base64 stream does.
fn base64_block(header: &[u8], data: &[u8], o: &VtuOptions) -> String {
    let e = base64::engine::general_purpose::STANDARD;
    if o.compress {
        let mut s = e.encode(header);
        s.push_str(&e.encode(data));
        s
    } else {
        let mut all = header.to_vec();
        all.extend_from_slice(data);
        e.encode(all)
    }
}

fn escape(s: &str) -> String {
    quick_xml::escape::escape(s).into_owned()
}

/// Each array's data as the format places it: inline text (ASCII, inline base64) or a block of
/// the appended section at an offset.
struct EncodedArrays {
    appended: Vec<Vec<u8>>,
    offsets: Vec<usize>,
    inline: Vec<Option<String>>,
}

fn encode_arrays(arrays: &[Array<'_>], o: &VtuOptions) -> EncodedArrays {
    // Encoded appended blocks and their offsets.
    let mut appended: Vec<Vec<u8>> = Vec::new();
    let mut offsets = Vec::new();
    let mut inline: Vec<Option<String>> = Vec::new();
    let mut offset = 0usize;
    for a in arrays {
        match o.format {
            VtuFormat::Ascii => {
                let mut s = String::with_capacity(a.len() * 8);
                for i in 0..a.len() {
                    if i > 0 {
                        s.push(if i % (6 * a.components.max(1)) == 0 {
                            '\n'
                        } else {
                            ' '
                        });
                    }
                    s.push_str(&a.text(i));
                }
                inline.push(Some(s));
                offsets.push(0);
            }
            VtuFormat::Binary => {
                let (h, d) = binary_block(&a.bytes(o.big_endian), o);
                inline.push(Some(base64_block(&h, &d, o)));
                offsets.push(0);
            }
            VtuFormat::Appended => {
                let (h, d) = binary_block(&a.bytes(o.big_endian), o);
                offsets.push(offset);
                offset += h.len() + d.len();
                appended.push(h);
                appended.push(d);
                inline.push(None);
            }
            VtuFormat::AppendedBase64 => {
                let (h, d) = binary_block(&a.bytes(o.big_endian), o);
                let s = base64_block(&h, &d, o).into_bytes();
                offsets.push(offset);
                offset += s.len();
                appended.push(s);
                inline.push(None);
            }
        }
    }
    EncodedArrays {
        appended,
        offsets,
        inline,
    }
}

fn write_to<W: Write>(mesh: &TetMesh, w: &mut W, o: &VtuOptions) -> std::io::Result<()> {
    let np = mesh.num_points();
    let nt = mesh.num_tets();
    // Int32 indices keep files small; Int64 only when the values would not fit.
    let conn_ty = if np <= i32::MAX as usize {
        Ty::I32
    } else {
        Ty::I64
    };
    let off_ty = if 4 * nt <= i32::MAX as usize {
        Ty::I32
    } else {
        Ty::I64
    };
    let scalar_name = if mesh.scalar_name.is_empty() {
        "scalar".to_string()
    } else {
        mesh.scalar_name.clone()
    };
    let arrays = [
        Array {
            name: scalar_name.clone(),
            components: 1,
            ty: Ty::F32,
            values: Values::Scalars(&mesh.scalars),
        },
        Array {
            name: "Points".into(),
            components: 3,
            ty: Ty::F32,
            values: Values::Points(&mesh.points),
        },
        Array {
            name: "connectivity".into(),
            components: 1,
            ty: conn_ty,
            values: Values::Conn(&mesh.tets),
        },
        Array {
            name: "offsets".into(),
            components: 1,
            ty: off_ty,
            values: Values::Offsets(nt),
        },
        Array {
            name: "types".into(),
            components: 1,
            ty: Ty::U8,
            values: Values::Types(nt),
        },
    ];
    let format = match o.format {
        VtuFormat::Ascii => "ascii",
        VtuFormat::Binary => "binary",
        VtuFormat::Appended | VtuFormat::AppendedBase64 => "appended",
    };
    let EncodedArrays {
        appended,
        offsets,
        inline,
    } = encode_arrays(&arrays, o);
    let array_xml = |w: &mut W, i: usize, indent: &str| -> std::io::Result<()> {
        let a = &arrays[i];
        write!(
            w,
            "{indent}<DataArray type=\"{}\" Name=\"{}\"",
            a.ty.name(),
            escape(&a.name)
        )?;
        if a.components != 1 {
            write!(w, " NumberOfComponents=\"{}\"", a.components)?;
        }
        write!(w, " format=\"{format}\"")?;
        match &inline[i] {
            None => writeln!(w, " offset=\"{}\"/>", offsets[i]),
            Some(text) => {
                writeln!(w, ">")?;
                w.write_all(text.as_bytes())?;
                writeln!(w, "\n{indent}</DataArray>")
            }
        }
    };
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    write!(
        w,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"{}\" header_type=\"{}\"",
        if o.big_endian {
            "BigEndian"
        } else {
            "LittleEndian"
        },
        if o.header64 { "UInt64" } else { "UInt32" }
    )?;
    if o.compress && o.format != VtuFormat::Ascii {
        write!(w, " compressor=\"vtkZLibDataCompressor\"")?;
    }
    writeln!(w, ">")?;
    writeln!(w, "  <UnstructuredGrid>")?;
    writeln!(
        w,
        "    <Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{nt}\">"
    )?;
    writeln!(w, "      <PointData Scalars=\"{}\">", escape(&scalar_name))?;
    array_xml(w, 0, "        ")?;
    writeln!(w, "      </PointData>")?;
    writeln!(w, "      <Points>")?;
    array_xml(w, 1, "        ")?;
    writeln!(w, "      </Points>")?;
    writeln!(w, "      <Cells>")?;
    for i in 2..5 {
        array_xml(w, i, "        ")?;
    }
    writeln!(w, "      </Cells>")?;
    writeln!(w, "    </Piece>")?;
    writeln!(w, "  </UnstructuredGrid>")?;
    if !appended.is_empty() {
        let enc = if o.format == VtuFormat::AppendedBase64 {
            "base64"
        } else {
            "raw"
        };
        write!(w, "  <AppendedData encoding=\"{enc}\">\n   _")?;
        for b in &appended {
            w.write_all(b)?;
        }
        writeln!(w, "\n  </AppendedData>")?;
    }
    writeln!(w, "</VTKFile>")?;
    Ok(())
}
