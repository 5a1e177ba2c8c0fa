//! TOFF, the text format of the HAVS / ZSWEEP distributions' tetrahedral meshes (SPX, F117…):
//! line 1 the vertex count, line 2 the tet count, then `x y z s` per vertex, then four
//! zero-based vertex indices per tet. The one scalar is called `scalar`.

use std::path::Path;

use crate::dataset::{Dataset, LoadOptions};
use crate::error::{ErrorKind, LoadError};
use crate::read_util as util;
use crate::TetMesh;

/// Name of the TOFF scalar.
pub const SCALAR_NAME: &str = "scalar";

/// Reads a TOFF file.
pub fn read(path: &Path, options: &LoadOptions) -> Result<Dataset, LoadError> {
    let bytes = util::read_file(path)?;
    from_bytes(&bytes, path, options)
}

/// Whether the head of a file looks like TOFF: two lines each holding one non-negative
/// integer, then (if present in `head`) a line of four numbers.
pub(crate) fn sniff(head: &[u8]) -> bool {
    let text = String::from_utf8_lossy(head);
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let one_int = |l: Option<&str>| {
        l.is_some_and(|l| l.split_whitespace().count() == 1 && l.parse::<u64>().is_ok())
    };
    if !one_int(lines.next()) || !one_int(lines.next()) {
        return false;
    }
    match lines.next() {
        Some(l) if head.len() > l.len() + 8 => {
            let v: Vec<&str> = l.split_whitespace().collect();
            v.len() == 4 && v.iter().all(|t| t.parse::<f64>().is_ok())
        }
        _ => true,
    }
}

struct Tokens<'a> {
    b: &'a [u8],
    pos: usize,
    path: &'a Path,
}

impl<'a> Tokens<'a> {
    fn next(&mut self) -> Option<(usize, &'a [u8])> {
        while self.pos < self.b.len() && self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < self.b.len() && !self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        (self.pos > start).then(|| (start, &self.b[start..self.pos]))
    }
    fn err(&self, at: usize, kind: ErrorKind) -> LoadError {
        LoadError::at(self.path, util::line_of(self.b, at), kind)
    }
    fn expect(&mut self, what: impl FnOnce() -> String) -> Result<(usize, &'a str), LoadError> {
        let Some((at, t)) = self.next() else {
            return Err(self.err(self.b.len(), ErrorKind::Truncated { expected: what() }));
        };
        match std::str::from_utf8(t) {
            Ok(s) => Ok((at, s)),
            Err(_) => Err(self.err(
                at,
                ErrorKind::Syntax {
                    expected: what(),
                    found: String::from_utf8_lossy(t).into_owned(),
                },
            )),
        }
    }
    fn count(&mut self, what: &str) -> Result<(usize, u64), LoadError> {
        let (at, s) = self.expect(|| what.to_string())?;
        let v = s.parse::<u64>().map_err(|_| {
            self.err(
                at,
                ErrorKind::Syntax {
                    expected: what.to_string(),
                    found: s.into(),
                },
            )
        })?;
        if v > u32::MAX as u64 {
            return Err(self.err(
                at,
                ErrorKind::IndexOverflow {
                    what: what.split(' ').next_back().unwrap_or(what).to_string(),
                    count: v,
                },
            ));
        }
        Ok((at, v))
    }
}

/// Parses TOFF text; `path` only names it in errors. Never panics on any input (fuzzed:
/// `datasets/fuzz`).
pub fn from_bytes(bytes: &[u8], path: &Path, options: &LoadOptions) -> Result<Dataset, LoadError> {
    if let Some(name) = &options.scalar {
        if name != SCALAR_NAME {
            return Err(LoadError::new(
                path,
                ErrorKind::MissingArray {
                    name: name.clone(),
                    available: vec![SCALAR_NAME.into()],
                },
            ));
        }
    }
    let mut t = Tokens {
        b: bytes,
        pos: 0,
        path,
    };
    let (_, nv) = t.count("the number of points")?;
    let (nt_at, nt) = t.count("the number of tets")?;
    // Every value needs at least one character and a separator: check the counts against the
    // bytes present before allocating anything from them.
    let left = (bytes.len() - t.pos) as u64;
    let need = ((nv + nt) * 4 * 2).saturating_sub(1);
    if nv + nt > 0 && need > left {
        return Err(t.err(
            bytes.len(),
            ErrorKind::Truncated { expected: format!("{nv} points (x y z s) and {nt} tets (4 indices) need at least {need} more bytes, only {left} remain") },
        ));
    }
    let nv = nv as usize;
    let nt = nt as usize;
    let mut points = Vec::with_capacity(nv);
    let mut scalars = Vec::with_capacity(nv);
    for i in 0..nv {
        let mut v = [0f32; 4];
        for (c, slot) in v.iter_mut().enumerate() {
            let what = || {
                format!(
                    "{} of point {i} ({} of {nv})",
                    ["x", "y", "z", "scalar"][c],
                    i + 1
                )
            };
            let (at, s) = t.expect(what)?;
            let x: f64 = s.parse().map_err(|_| {
                t.err(
                    at,
                    ErrorKind::Syntax {
                        expected: what(),
                        found: s.into(),
                    },
                )
            })?;
            let f = x as f32;
            if !f.is_finite() {
                let w = if c == 3 {
                    "scalar of point"
                } else {
                    "coordinate of point"
                };
                return Err(t.err(
                    at,
                    ErrorKind::NonFinite {
                        what: w.into(),
                        index: i as u64,
                        value: x,
                    },
                ));
            }
            *slot = f;
        }
        points.push([v[0], v[1], v[2]]);
        scalars.push(v[3]);
    }
    let mut tets = Vec::with_capacity(nt);
    for i in 0..nt {
        let mut tet = [0u32; 4];
        for (c, slot) in tet.iter_mut().enumerate() {
            let what = || format!("vertex {c} of tet {i} ({} of {nt})", i + 1);
            let (at, s) = t.expect(what)?;
            let v: i64 = s.parse().map_err(|_| {
                t.err(
                    at,
                    ErrorKind::Syntax {
                        expected: format!("{} (an integer index)", what()),
                        found: s.into(),
                    },
                )
            })?;
            if v < 0 {
                return Err(t.err(
                    at,
                    ErrorKind::Syntax {
                        expected: format!("{} (a zero-based index)", what()),
                        found: s.into(),
                    },
                ));
            }
            if v as u64 >= nv as u64 {
                return Err(t.err(
                    at,
                    ErrorKind::IndexOutOfRange {
                        what: "point".into(),
                        index: v as u64,
                        limit: nv as u64,
                    },
                ));
            }
            *slot = v as u32;
        }
        tets.push(tet);
    }
    if let Some((at, tok)) = t.next() {
        return Err(t.err(
            at,
            ErrorKind::Syntax {
                expected: format!("the end of the file after {nt} tets"),
                found: String::from_utf8_lossy(tok).into_owned(),
            },
        ));
    }
    let mesh = TetMesh::new(util::stem_name(path), points, scalars, SCALAR_NAME, tets).map_err(
        |k| match k {
            ErrorKind::EmptyMesh(_) => t.err(nt_at, k),
            k => LoadError::new(path, k),
        },
    )?;
    Ok(Dataset {
        mesh,
        volume: None,
        source: path.display().to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Location;

    const TWO: &str = "5\n2\n0 0 0 0.5\n1 0 0 1\n0 1 0 2\n0 0 1 3\n1 1 1 4\n0 1 2 3\n1 2 3 4\n";

    #[test]
    fn reads_two_tets() {
        let ds = from_bytes(
            TWO.as_bytes(),
            Path::new("two.toff"),
            &LoadOptions::default(),
        )
        .unwrap();
        assert_eq!(ds.mesh.num_points(), 5);
        assert_eq!(ds.mesh.num_tets(), 2);
        assert_eq!(ds.mesh.scalars[0], 0.5);
        assert_eq!(ds.mesh.scalar_name, "scalar");
        assert!(sniff(TWO.as_bytes()));
        assert!(!sniff(b"OFF\n4 4 6\n"));
    }

    #[test]
    fn located_errors() {
        let bad = TWO.replace("1 2 3 4", "1 2 3 5");
        let err =
            from_bytes(bad.as_bytes(), Path::new("b.toff"), &LoadOptions::default()).unwrap_err();
        assert_eq!(
            err.kind,
            ErrorKind::IndexOutOfRange {
                what: "point".into(),
                index: 5,
                limit: 5
            }
        );
        assert_eq!(err.location, Some(Location::Line(9)));
        let bad = TWO.replace("0 1 0 2", "0 nan 0 2");
        let err =
            from_bytes(bad.as_bytes(), Path::new("b.toff"), &LoadOptions::default()).unwrap_err();
        assert!(
            matches!(err.kind, ErrorKind::NonFinite { index: 2, .. }),
            "{err}"
        );
        assert_eq!(err.location, Some(Location::Line(5)));
    }

    // Quick stand-in for the TOFF fuzz target (datasets/fuzz) that CI runs every time.
    proptest::proptest! {
        #[test]
        fn random_and_corrupted_input_never_panics(
            data in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300),
            edits in proptest::collection::vec((proptest::prelude::any::<usize>(), 0u8..128), 1..6),
        ) {
            let _ = from_bytes(&data, Path::new("r.toff"), &LoadOptions::default());
            let mut b = TWO.as_bytes().to_vec();
            for (at, v) in edits {
                let i = at % b.len();
                b[i] = v;
            }
            let _ = from_bytes(&b, Path::new("c.toff"), &LoadOptions::default());
        }
    }
}
