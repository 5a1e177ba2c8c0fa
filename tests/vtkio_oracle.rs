//! vtkio (0.7, an independent Rust VTK reader) as the oracle of our hand-written VTK readers.
//!
//! Every VTK file the project can meet is read by both: the data directory's `.vtk`/`.vtu`
//! files, the legacy reader's fuzz seeds, files written by VTK itself
//! (`datasets/testdata/vtk-written`), the malformed corpus (`tests/malformed_vtk.rs`) and
//! what our `.vtu` writer produces in each of its layouts for several generated meshes. vtkio's
//! model goes through the same cell split and mesh checks as ours (`vtkio_model.rs`), so:
//!
//! - where vtkio reads a file, points, tets, the scalar (every array, by name), the array names
//!   and the grid parameters must be identical, bit for bit, and where the shared checks reject
//!   vtkio's model, our reader must reject the file with the same kind of error;
//! - where vtkio refuses a file, [`VTKIO_REFUSES`] must say so and why, and our reader's outcome
//!   on it is asserted here (and its exact error in `malformed_inputs.rs`);
//! - [`KNOWN_DIFFERENCES`] lists the files whose outcomes differ on purpose.
//!
//! An entry of either table that no longer happens fails the test, so the tables stay true.

#[path = "vtkio_model.rs"]
mod vtkio_model;

use std::path::{Path, PathBuf};

use datasets::load::{load, Format};
use datasets::write_vtu::{write_vtu_with, VtuFormat, VtuOptions};
use datasets::{ErrorKind, LoadError, LoadOptions, TetMesh};
use vtkio_model::{VtkioMesh, VtkioOutcome};

/// Files vtkio 0.7.0-rc2 refuses: (key pattern, `*` = any text; a piece of vtkio's error; why).
/// vtkio's legacy errors are bare nom error kinds (`Tag`, `Digit`, `Complete`, …): no line, no
/// byte offset, no statement of what was expected — one reason our readers stay hand-written.
const VTKIO_REFUSES: &[(&str, &str, &str)] = &[
    // Valid files vtkio cannot read (its limitations, not faults of the files).
    (
        "data/Tetrahedron.vtu",
        "unknown variant `raw`",
        "raw appended data, ParaView's default: vtkio reads <AppendedData> only as base64 (its raw \
         path is behind a `binary` cfg that its Cargo.toml does not declare)",
    ),
    (
        "vtk-written/wavelet-raw-zlib.vti",
        "unknown variant `raw`",
        "VTK's own raw appended, zlib-compressed image data: as above",
    ),
    (
        "writer/*/appended-*",
        "unknown variant `raw`",
        "our writer's raw appended layouts (the default of `datasets convert`): as above",
    ),
    (
        "data/ironProt.vtk",
        "Parse error: Tag",
        "blank lines between header lines (VTK's own ironProt.vtk, version 1.0 with ASPECT_RATIO): \
         vtkio wants each keyword on the very next line",
    ),
    (
        "seed/binary42.vtk",
        "Parse error: Tag",
        "data type unsigned_short: vtkio's legacy parser has no unsigned_short",
    ),
    (
        "malformed/structured_points_overflowing_u32",
        "Parse error: Tag",
        "STRUCTURED_POINTS without ORIGIN and SPACING (VTK defaults them to 0 and 1): vtkio \
         requires both; ours reads further and reports the 10^15-point grid (IndexOverflow)",
    ),
    (
        "malformed/structured_points_without_data",
        "Parse error: Tag",
        "no ORIGIN line, as above; ours reports the grid has no data (MissingArray)",
    ),
    // Malformed files both refuse; ours names the line or byte and the fault
    // (`malformed_inputs.rs` checks each), vtkio gives only a nom error kind.
    ("malformed/not_a_vtk_header", "Parse error: Tag", "no VTK header"),
    (
        "malformed/unsupported_version",
        "Parse error: Tag",
        "version 6.0 does not exist",
    ),
    (
        "malformed/truncated_points",
        "Parse error: Complete",
        "POINTS cut short",
    ),
    (
        "malformed/absurd_point_count",
        "Parse error: Complete",
        "10^9 points announced in a 100-byte file",
    ),
    (
        "malformed/point_count_overflowing_u32",
        "Parse error: Digit",
        "5·10^9 points: vtkio reads counts as u32",
    ),
    (
        "malformed/nan_coordinate",
        "Parse error: Digit",
        "a `nan` coordinate: vtkio's number parser rejects the token; ours reads it and reports \
         the non-finite point (NonFinite)",
    ),
    (
        "malformed/infinite_scalar",
        "Parse error: Digit",
        "an `inf` scalar: as above",
    ),
    (
        "malformed/no_cells",
        "Parse error: Tag",
        "no CELLS section: vtkio requires one; ours reports an empty mesh",
    ),
    (
        "malformed/bad_number",
        "Parse error: Digit",
        "a word among the coordinates",
    ),
    (
        "malformed/binary_little_endian",
        "Parse error: MapOpt",
        "little-endian BINARY data: vtkio fails on the cell types; ours names the byte order",
    ),
    (
        "malformed/binary_truncated",
        "Parse error: Complete",
        "BINARY file cut inside CELL_TYPES",
    ),
];

/// Files whose outcomes differ on purpose: (key pattern, why).
const KNOWN_DIFFERENCES: &[(&str, &str)] = &[(
    "malformed/cells_size_mismatch",
    "`CELLS 2 11` over 10 values: vtkio ignores the size and takes the cells by their counts; \
     ours refuses the file, as VTK's reader, which reads `size` values, would read CELL_TYPES as \
     a number",
)];

/// One file of the corpus.
struct Input {
    /// `data/…`, `seed/…`, `malformed/…` or `writer/…`.
    key: String,
    path: PathBuf,
    scalar: Option<String>,
    /// For files our writer made: the mesh written.
    written: Option<TetMesh>,
}

/// How the two readers' outcomes on one file relate.
#[derive(Debug)]
enum Verdict {
    /// Both read it: identical meshes for each of `arrays` arrays.
    Same { tets: usize, arrays: usize },
    /// Both rejected it with the same kind of error.
    BothReject(String),
    /// vtkio refused it; our outcome.
    VtkioRefused { vtkio: String, ours: String },
    /// Anything else.
    Differ(String),
}

fn matches_pattern(pattern: &str, key: &str) -> bool {
    let mut rest = key;
    let parts: Vec<&str> = pattern.split('*').collect();
    for (i, part) in parts.iter().enumerate() {
        if i == 0 {
            match rest.strip_prefix(part) {
                Some(r) => rest = r,
                None => return false,
            }
        } else if i == parts.len() - 1 {
            return rest.ends_with(part);
        } else {
            match rest.find(part) {
                Some(at) => rest = &rest[at + part.len()..],
                None => return false,
            }
        }
    }
    rest.is_empty()
}

fn kind_name(k: &ErrorKind) -> String {
    format!("{k:?}")
        .split(|c: char| !c.is_alphanumeric())
        .next()
        .unwrap_or("")
        .to_string()
}

fn options(scalar: Option<&str>) -> LoadOptions {
    LoadOptions {
        scalar: scalar.map(String::from),
        ..Default::default()
    }
}

/// Our reader's array names: asking for an array no file has lists them in the error.
fn our_array_names(path: &Path) -> Vec<String> {
    match load(path, &options(Some("\u{1}no such array\u{1}"))) {
        Err(LoadError {
            kind: ErrorKind::MissingArray { available, .. },
            ..
        }) => available,
        other => panic!("{}: listing arrays gave {other:?}", path.display()),
    }
}

/// First difference between two meshes (points, tets, scalars, scalar name, repairs).
fn mesh_difference(ours: &TetMesh, theirs: &TetMesh) -> Option<String> {
    geometry_difference(ours, theirs).or_else(|| {
        let r = |m: &TetMesh| (m.repair.degenerate_dropped, m.repair.inverted_fixed);
        (r(ours) != r(theirs)).then(|| {
            format!(
                "repairs (dropped, inverted) {:?} vs vtkio's {:?}",
                r(ours),
                r(theirs)
            )
        })
    })
}

/// First difference in points, tets, scalars or scalar name.
fn geometry_difference(ours: &TetMesh, theirs: &TetMesh) -> Option<String> {
    if ours.points.len() != theirs.points.len() {
        return Some(format!(
            "{} points vs vtkio's {}",
            ours.points.len(),
            theirs.points.len()
        ));
    }
    if let Some(i) = (0..ours.points.len()).find(|&i| ours.points[i] != theirs.points[i]) {
        return Some(format!(
            "point {i}: {:?} vs vtkio's {:?}",
            ours.points[i], theirs.points[i]
        ));
    }
    if ours.tets != theirs.tets {
        let i = (0..ours.tets.len().min(theirs.tets.len()))
            .find(|&i| ours.tets[i] != theirs.tets[i])
            .unwrap_or(ours.tets.len().min(theirs.tets.len()));
        return Some(format!(
            "tets differ from tet {i} ({} vs vtkio's {})",
            ours.tets.len(),
            theirs.tets.len()
        ));
    }
    if ours.scalar_name != theirs.scalar_name {
        return Some(format!(
            "scalar {:?} vs vtkio's {:?}",
            ours.scalar_name, theirs.scalar_name
        ));
    }
    if let Some(i) = (0..ours.scalars.len()).find(|&i| ours.scalars[i] != theirs.scalars[i]) {
        return Some(format!(
            "scalar {} at point {i}: {} vs vtkio's {}",
            ours.scalar_name, ours.scalars[i], theirs.scalars[i]
        ));
    }
    None
}

/// Reads `input` with both readers and compares.
fn compare(input: &Input) -> Verdict {
    let bytes = std::fs::read(&input.path).unwrap();
    let format = vtkio_model::vtk_format(&input.path).unwrap_or(Format::VtkLegacy);
    let scalar = input.scalar.as_deref();
    let ours = load(&input.path, &options(scalar));
    let theirs = vtkio_model::read(&bytes, format, scalar);
    let describe = |r: &Result<datasets::Dataset, LoadError>| match r {
        Ok(ds) => format!("reads ({} tets)", ds.mesh.num_tets()),
        Err(e) => format!("{} ({e})", kind_name(&e.kind)),
    };
    match (ours, theirs) {
        (ours, VtkioOutcome::Refused(msg)) => Verdict::VtkioRefused {
            vtkio: msg,
            ours: describe(&ours),
        },
        (Err(e), VtkioOutcome::Parsed(Err(k))) => {
            if kind_name(&e.kind) == kind_name(&k) {
                Verdict::BothReject(kind_name(&k))
            } else {
                Verdict::Differ(format!("ours: {e}; vtkio's model: {k}"))
            }
        }
        (Ok(ds), VtkioOutcome::Parsed(Err(k))) => Verdict::Differ(format!(
            "ours reads ({} tets); vtkio's model is rejected: {k}",
            ds.mesh.num_tets()
        )),
        (Err(e), VtkioOutcome::Parsed(Ok(m))) => Verdict::Differ(format!(
            "ours: {e}; vtkio's model gives {} tets",
            m.mesh.num_tets()
        )),
        (Ok(ds), VtkioOutcome::Parsed(Ok(m))) => compare_read(input, &bytes, format, &ds, &m),
    }
}

/// Both read the file: compare the default mesh, the grid, the array names and every array.
fn compare_read(
    input: &Input,
    bytes: &[u8],
    format: Format,
    ds: &datasets::Dataset,
    m: &VtkioMesh,
) -> Verdict {
    if let Some(d) = mesh_difference(&ds.mesh, &m.mesh) {
        return Verdict::Differ(d);
    }
    let grid = ds.volume.as_ref().map(|v| (v.dims, v.origin, v.spacing));
    if grid != m.grid {
        return Verdict::Differ(format!("grid {grid:?} vs vtkio's {:?}", m.grid));
    }
    let names = if input.scalar.is_some() {
        m.arrays.clone()
    } else {
        our_array_names(&input.path)
    };
    if names != m.arrays {
        return Verdict::Differ(format!("arrays {names:?} vs vtkio's {:?}", m.arrays));
    }
    for name in &names {
        let ours = load(&input.path, &options(Some(name)));
        let theirs = vtkio_model::read(bytes, format, Some(name));
        match (ours, theirs) {
            (Ok(o), VtkioOutcome::Parsed(Ok(t))) => {
                if let Some(d) = mesh_difference(&o.mesh, &t.mesh) {
                    return Verdict::Differ(format!("array {name}: {d}"));
                }
            }
            (o, VtkioOutcome::Parsed(Err(k))) => {
                let same = matches!(&o, Err(e) if kind_name(&e.kind) == kind_name(&k));
                if !same {
                    return Verdict::Differ(format!("array {name}: ours {o:?}, vtkio's {k}"));
                }
            }
            (o, _) => return Verdict::Differ(format!("array {name}: ours {o:?}, vtkio refused")),
        }
    }
    if let Some(w) = &input.written {
        // The written mesh was already repaired; reading it back must repair nothing.
        if let Some(d) = geometry_difference(&ds.mesh, w) {
            return Verdict::Differ(format!("written mesh not read back: {d}"));
        }
    }
    Verdict::Same {
        tets: ds.mesh.num_tets(),
        arrays: names.len(),
    }
}

/// Every layout our `.vtu` writer offers (ASCII has no compression and no byte order).
fn writer_layouts() -> Vec<(String, VtuOptions)> {
    let mut v = Vec::new();
    for (fname, format) in [
        ("ascii", VtuFormat::Ascii),
        ("binary", VtuFormat::Binary),
        ("appended", VtuFormat::Appended),
        ("appended-base64", VtuFormat::AppendedBase64),
    ] {
        for compress in [false, true] {
            for header64 in [false, true] {
                for big_endian in [false, true] {
                    if format == VtuFormat::Ascii && (compress || big_endian) {
                        continue;
                    }
                    let name = format!(
                        "{fname}{}-{}-{}",
                        if compress { "-zlib" } else { "" },
                        if header64 { "u64" } else { "u32" },
                        if big_endian { "be" } else { "le" }
                    );
                    let o = VtuOptions {
                        format,
                        compress,
                        header64,
                        big_endian,
                    };
                    v.push((name, o));
                }
            }
        }
    }
    v
}

fn corpus(tmp: &Path) -> Vec<Input> {
    let mut inputs = Vec::new();
    let input = |key: String, path: PathBuf| Input {
        key,
        path,
        scalar: None,
        written: None,
    };
    if let Some(dir) = tetbench_tests::data_dir() {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| vtkio_model::vtk_format(p).is_some())
            .collect();
        files.sort();
        for p in files {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            inputs.push(input(format!("data/{name}"), p));
        }
    }
    // The legacy reader's fuzz seeds, and files VTK's own XML writers made (the XML reader's
    // unit tests use them too).
    let datasets_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../datasets");
    for (prefix, dir) in [
        ("seed", "fuzz/seeds/vtk_legacy"),
        ("vtk-written", "testdata/vtk-written"),
    ] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(datasets_dir.join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        for p in files {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            inputs.push(input(format!("{prefix}/{name}"), p));
        }
    }
    for c in tetbench_tests::malformed_vtk::cases() {
        let dir = tmp.join("malformed").join(c.case);
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(c.file);
        std::fs::write(&path, &c.bytes).unwrap();
        inputs.push(Input {
            key: format!("malformed/{}", c.case),
            path,
            scalar: c.scalar.map(String::from),
            written: None,
        });
    }
    // Convex, non-convex and sliver-heavy meshes; one scalar name that needs XML escaping.
    for (spec, seed) in [
        ("box:1k:field=linear", 1),
        ("shell:2k:field=ml", 2),
        ("slivers:3k:field=blobs", 5),
    ] {
        let mut mesh = datasets::generate::from_spec(spec, seed).unwrap();
        if spec.starts_with("slivers") {
            mesh.scalar_name = "a <strange> & \"quoted\" name".into();
        }
        let dir = tmp.join("writer").join(spec.replace([':', '='], "_"));
        std::fs::create_dir_all(&dir).unwrap();
        for (layout, o) in writer_layouts() {
            let path = dir.join(format!("{layout}.vtu"));
            write_vtu_with(&mesh, &path, &o).unwrap();
            inputs.push(Input {
                key: format!("writer/{spec}/{layout}"),
                path,
                scalar: None,
                written: Some(mesh.clone()),
            });
        }
    }
    inputs
}

#[test]
fn vtkio_reads_what_our_readers_read() {
    let tmp = tempfile::tempdir().unwrap();
    let inputs = corpus(tmp.path());
    let mut failures = Vec::new();
    let mut used_refusals = vec![false; VTKIO_REFUSES.len()];
    let mut used_differences = vec![false; KNOWN_DIFFERENCES.len()];
    let (mut same, mut both_reject, mut refused, mut differ) = (0, 0, 0, 0);
    let (mut tets_compared, mut arrays_compared) = (0, 0);
    let mut reject_kinds: Vec<String> = Vec::new();
    // Per reader (legacy, XML): files, read by ours, read by vtkio.
    let mut per_reader = [[0usize; 3]; 2];
    println!("| file | verdict |\n|---|---|");
    for input in &inputs {
        let verdict = compare(input);
        println!("| {} | {verdict:?} |", input.key);
        let xml = vtkio_model::vtk_format(&input.path) == Some(Format::VtkXml);
        let counts = &mut per_reader[xml as usize];
        counts[0] += 1;
        counts[1] += load(&input.path, &options(input.scalar.as_deref())).is_ok() as usize;
        counts[2] += matches!(verdict, Verdict::Same { .. }) as usize;
        match &verdict {
            Verdict::Same { tets, arrays } => {
                same += 1;
                tets_compared += tets;
                arrays_compared += arrays;
            }
            Verdict::BothReject(kind) => {
                both_reject += 1;
                reject_kinds.push(kind.clone());
            }
            Verdict::VtkioRefused { vtkio, ours } => {
                refused += 1;
                let entry = VTKIO_REFUSES.iter().position(|(pat, msg, _)| {
                    matches_pattern(pat, &input.key) && vtkio.contains(msg)
                });
                match entry {
                    Some(i) => used_refusals[i] = true,
                    None => failures.push(format!(
                        "{}: vtkio refuses it ({vtkio}), not in VTKIO_REFUSES; ours {ours}",
                        input.key
                    )),
                }
                // Our reader's outcome on what vtkio refuses: valid files must read (written
                // ones back to the written mesh, checked here), malformed ones must fail.
                let must_read = !input.key.starts_with("malformed/")
                    || input.key == "malformed/well_formed_base";
                if must_read != ours.starts_with("reads") {
                    failures.push(format!("{}: ours {ours}", input.key));
                }
                if let Some(w) = &input.written {
                    let ds = load(&input.path, &LoadOptions::default()).unwrap();
                    if let Some(d) = geometry_difference(&ds.mesh, w) {
                        failures.push(format!("{}: written mesh not read back: {d}", input.key));
                    }
                }
            }
            Verdict::Differ(d) => {
                differ += 1;
                match KNOWN_DIFFERENCES
                    .iter()
                    .position(|(pat, _)| matches_pattern(pat, &input.key))
                {
                    Some(i) => used_differences[i] = true,
                    None => failures.push(format!("{}: {d}", input.key)),
                }
            }
        }
    }
    println!(
        "{} files: {same} read identically by both, {both_reject} rejected by both with the same \
         kind of error, {refused} refused by vtkio, {differ} listed differences",
        inputs.len()
    );
    println!(
        "compared: {tets_compared} tets and {arrays_compared} arrays; rejected by both: {}",
        reject_kinds.join(", ")
    );
    for (name, [n, ours, theirs]) in ["legacy", "XML"].iter().zip(per_reader) {
        println!(
            "{name} VTK: {n} files, our reader reads {ours}, vtkio reads {theirs} (identically)"
        );
    }
    // Without the data directory (a checkout without ../shared) its entries cannot happen.
    let have_data = inputs.iter().any(|i| i.key.starts_with("data/"));
    for (i, used) in used_refusals.iter().enumerate() {
        if !used && (have_data || !VTKIO_REFUSES[i].0.starts_with("data/")) {
            failures.push(format!(
                "VTKIO_REFUSES entry {:?} no longer happens",
                VTKIO_REFUSES[i].0
            ));
        }
    }
    for (i, used) in used_differences.iter().enumerate() {
        if !used {
            failures.push(format!(
                "KNOWN_DIFFERENCES entry {:?} no longer happens",
                KNOWN_DIFFERENCES[i].0
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
