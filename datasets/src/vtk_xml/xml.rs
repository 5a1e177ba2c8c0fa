//! The XML side of a VTK XML file: a minimal element tree built with quick-xml, after the raw
//! appended block (binary, not XML text) has been cut off.

use std::path::Path;

use quick_xml::events::{BytesStart, Event};

use super::{Appended, XmlFile};
use crate::error::{ErrorKind, LoadError, Location};

// ---------------------------------------------------------------------------------------------
// A minimal element tree (the XML part of a VTK file is small; array payloads are kept as text
// or addressed in the appended block).

#[derive(Debug, Default)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) attrs: Vec<(String, String)>,
    pub(super) children: Vec<Element>,
    /// Concatenated text content (only arrays carry any that matters).
    pub(super) text: Vec<u8>,
    /// Byte offset of the start tag and of the first text.
    pub(super) pos: u64,
    pub(super) text_pos: u64,
}

impl Element {
    pub(super) fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
    pub(super) fn child(&self, name: &str) -> Option<&Element> {
        self.children.iter().find(|c| c.name == name)
    }
    pub(super) fn children_named<'a>(
        &'a self,
        name: &'a str,
    ) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
}

pub(super) fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

pub(super) fn rfind(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).rposition(|w| w == needle)
}

impl<'a> XmlFile<'a> {
    pub(super) fn parse(bytes: &'a [u8], path: &'a Path) -> Result<XmlFile<'a>, LoadError> {
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
}

pub(super) fn line_of(bytes: &[u8], pos: u64) -> usize {
    let end = (pos as usize).min(bytes.len());
    bytes[..end].iter().filter(|&&b| b == b'\n').count() + 1
}

pub(super) fn first_name(el: &Element) -> String {
    el.children
        .first()
        .map(|c| format!("<{}>", c.name))
        .unwrap_or_else(|| "nothing".into())
}

pub(super) fn start_element(
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
pub(super) fn parse_tree(xml: &[u8], path: &Path, cut: bool) -> Result<Element, LoadError> {
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
