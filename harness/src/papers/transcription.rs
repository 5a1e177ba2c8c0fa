//! The papers' tables as data: the CSVs of `reports/papers/` (transcribed from the papers, one
//! per table) and the side list of cells the transcription calls uncertain
//! (`reports/papers/uncertain.csv`). They are compiled into the binary, so `tetbench
//! reproduce` works from any directory. This is the one reader of those files.

use anyhow::{anyhow, Context};

/// Every paper table CSV, by name (file name without `.csv`).
pub const CSVS: &[(&str, &str)] = &[
    (
        "havs_table1",
        include_str!("../../../reports/papers/havs_table1.csv"),
    ),
    (
        "havs_table2",
        include_str!("../../../reports/papers/havs_table2.csv"),
    ),
    (
        "havs_table3",
        include_str!("../../../reports/papers/havs_table3.csv"),
    ),
    (
        "havs_table4",
        include_str!("../../../reports/papers/havs_table4.csv"),
    ),
    (
        "havs_table5",
        include_str!("../../../reports/papers/havs_table5.csv"),
    ),
    (
        "gator_table1",
        include_str!("../../../reports/papers/gator_table1.csv"),
    ),
    (
        "gator_table2",
        include_str!("../../../reports/papers/gator_table2.csv"),
    ),
    (
        "gator_table3",
        include_str!("../../../reports/papers/gator_table3.csv"),
    ),
    (
        "fragment-pt_table1",
        include_str!("../../../reports/papers/fragment-pt_table1.csv"),
    ),
    (
        "fragment-pt_table2",
        include_str!("../../../reports/papers/fragment-pt_table2.csv"),
    ),
    (
        "raycast_table3",
        include_str!("../../../reports/papers/raycast_table3.csv"),
    ),
    (
        "raycast_table4",
        include_str!("../../../reports/papers/raycast_table4.csv"),
    ),
    (
        "raycast_table5",
        include_str!("../../../reports/papers/raycast_table5.csv"),
    ),
    (
        "raycast_table6",
        include_str!("../../../reports/papers/raycast_table6.csv"),
    ),
    (
        "splat_table1",
        include_str!("../../../reports/papers/splat_table1.csv"),
    ),
];

const UNCERTAIN: &str = include_str!("../../../reports/papers/uncertain.csv");

/// One paper table: header and rows of text cells (empty = not given by the paper).
#[derive(Debug, Clone)]
pub struct PaperTable {
    pub name: String,
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl PaperTable {
    fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The key naming a row: `gpu / dataset` where the table is per GPU, else its first cell.
    pub fn row_key(&self, row: &[String]) -> String {
        match (self.column("gpu"), self.column("dataset")) {
            (Some(g), Some(d)) => format!("{} / {}", row[g], row[d]),
            _ => row.first().cloned().unwrap_or_default(),
        }
    }

    /// Every row key, in the table's order.
    pub fn keys(&self) -> Vec<String> {
        self.rows.iter().map(|r| self.row_key(r)).collect()
    }

    /// The text of a cell (row by key, column by name).
    pub fn text(&self, key: &str, column: &str) -> Option<&str> {
        let c = self.column(column)?;
        self.rows
            .iter()
            .find(|r| self.row_key(r) == key)
            .map(|r| r[c].as_str())
    }

    /// A numeric cell; `None` where the paper gives no value.
    pub fn value(&self, key: &str, column: &str) -> Option<f64> {
        self.text(key, column)
            .filter(|t| !t.trim().is_empty())
            .and_then(|t| t.trim().parse().ok())
    }

    /// Why the transcription calls this cell uncertain, if it does.
    pub fn uncertain(&self, key: &str, column: &str) -> Option<String> {
        let (paper, table) = self.name.split_once('_')?;
        uncertain(paper, table, key, column)
    }
}

/// A CSV reader over one of our data files (claims, rule history, hardware) whose header must
/// be exactly `expected`; the error names the file and both headers.
pub fn reader_with_header<'t>(
    text: &'t str,
    file: &str,
    expected: &[&str],
) -> anyhow::Result<csv::Reader<&'t [u8]>> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(text.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .with_context(|| format!("{file}: header"))?
        .iter()
        .map(str::to_string)
        .collect();
    if header != expected {
        return Err(anyhow!(
            "{file}: header is {header:?}, expected {}",
            expected.join(",")
        ));
    }
    Ok(reader)
}

/// The records of a CSV file with the header `expected`, each deserialised into `T` with its
/// line; an error names the file, the line, the column and what is wrong. Fields are trimmed.
pub fn deserialize_rows<T: serde::de::DeserializeOwned>(
    text: &str,
    file: &str,
    expected: &[&str],
) -> anyhow::Result<Vec<(u64, T)>> {
    reader_with_header(text, file, expected)?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let headers = reader.headers()?.clone();
    let mut out = vec![];
    for rec in reader.records() {
        let rec = rec.with_context(|| format!("{file}: a record"))?;
        let line = rec.position().map_or(0, |p| p.line());
        match rec.deserialize::<T>(Some(&headers)) {
            Ok(t) => out.push((line, t)),
            Err(e) => {
                let what = match e.kind() {
                    csv::ErrorKind::Deserialize { err, .. } => {
                        let column = err
                            .field()
                            .and_then(|i| expected.get(i as usize))
                            .map_or(String::new(), |c| format!("column {c}: "));
                        format!("{column}{}", err.kind())
                    }
                    _ => e.to_string(),
                };
                return Err(anyhow!("{file}: line {line}: {what}"));
            }
        }
    }
    Ok(out)
}

/// The paper's row name of a registry data set in the tables of `paper` (`havs`, `gator`,
/// `fragment-pt`, `raycast`), where the paper names it differently.
pub fn paper_name(paper: &str, dataset: &str) -> Option<&'static str> {
    let names: &[(&str, &str)] = match paper {
        "havs" => &[
            ("f117", "f117"),
            ("kew", "kew"),
            ("spx2", "spx2"),
            ("torso", "torso"),
            ("fighter", "fighter"),
        ],
        "gator" => &[
            ("bluntfin", "Blunt Fin"),
            ("post", "Oxygen Post"),
            ("deltawing", "Delta Wing"),
        ],
        "fragment-pt" => &[
            ("spx", "Spx"),
            ("bluntfin", "Blunt"),
            ("comb", "Comb"),
            ("post", "Post"),
            ("spx2", "Spx2"),
            ("fuel", "Fuel"),
            ("brain", "Brain"),
        ],
        "raycast" => &[("spx1", "spx1"), ("bluntfin", "blunt"), ("f117", "f117")],
        "splat" => &[
            ("lobster", "Lobster"),
            ("engine", "Engine"),
            ("teapot", "BostonTeapot"),
            ("aneurism", "Aneurism"),
            ("bonsai", "Bonsai"),
            ("stagbeetle", "StagBeetle"),
        ],
        _ => &[],
    };
    names
        .iter()
        .find(|(d, _)| d.eq_ignore_ascii_case(dataset))
        .map(|(_, p)| *p)
}

/// The paper's tets/s for a result series, where a paper table gives one: GATOR Table 3
/// (constant or linear cells), HAVS Table 4 (k = 2, whole frames), fragment PT Table 1.
/// Returns (source, value).
pub fn paper_tets_per_sec(
    algorithm: &str,
    settings: &render_core::Settings,
    dataset: &str,
) -> Option<(&'static str, f64)> {
    let get = |paper: &str, t: &str, col: &str| {
        let name = paper_name(paper, dataset)?;
        table(t).ok()?.value(name, col)
    };
    match algorithm {
        "gator-pt" => {
            let v = settings.text("variant")?;
            let col = format!("{v}_tets_per_sec");
            get("gator", "gator_table3", &col).map(|x| ("GATOR Table 3", x))
        }
        "havs" if settings.int("k") == Some(2) => {
            get("havs", "havs_table4", "tets_per_sec").map(|x| ("HAVS Table 4 (k=2)", x))
        }
        "fragment-pt" => get("fragment-pt", "fragment-pt_table1", "tets_per_sec")
            .map(|x| ("fragment PT Table 1", x)),
        _ => None,
    }
}

/// Columns that name a row rather than hold a value.
pub fn is_key_column(name: &str) -> bool {
    matches!(
        name,
        "dataset" | "gpu" | "algorithm" | "sort_algorithm" | "case"
    )
}

/// One of the embedded tables, which all parse (`every_paper_csv_parses_with_its_rows`).
pub fn embedded(name: &str) -> PaperTable {
    table(name).expect("embedded paper CSV parses (tested)")
}

/// Parses one embedded CSV; every row must have the header's number of cells, and every cell
/// other than the key columns must be empty or a number.
pub fn table(name: &str) -> anyhow::Result<PaperTable> {
    let (_, text) = CSVS
        .iter()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| anyhow!("no paper table {name:?}"))?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(text.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .with_context(|| format!("reports/papers/{name}.csv: header"))?
        .iter()
        .map(str::to_string)
        .collect();
    let mut rows = vec![];
    for (i, rec) in reader.records().enumerate() {
        let rec = rec.with_context(|| format!("reports/papers/{name}.csv: row {}", i + 2))?;
        let row: Vec<String> = rec.iter().map(str::to_string).collect();
        for (c, cell) in row.iter().enumerate() {
            let key_column = is_key_column(&header[c]);
            if !key_column && !cell.trim().is_empty() && cell.trim().parse::<f64>().is_err() {
                anyhow::bail!(
                    "reports/papers/{name}.csv: row {}, column {}: {cell:?} is not a number",
                    i + 2,
                    header[c]
                );
            }
        }
        rows.push(row);
    }
    Ok(PaperTable {
        name: name.to_string(),
        header,
        rows,
    })
}

/// Why the transcription calls a cell uncertain (`*` in the side list matches any row or
/// column).
pub fn uncertain(paper: &str, table: &str, key: &str, column: &str) -> Option<String> {
    let mut reader = csv::Reader::from_reader(UNCERTAIN.as_bytes());
    reader.records().flatten().find_map(|r| {
        let m = |i: usize, v: &str| r.get(i).is_some_and(|c| c == "*" || c == v);
        (r.get(0) == Some(paper) && r.get(1) == Some(table) && m(2, key) && m(3, column))
            .then(|| r.get(4).unwrap_or("").to_string())
    })
}

/// Every uncertain cell of the side list (for its test): (paper, table, row, column).
pub fn uncertain_cells() -> anyhow::Result<Vec<[String; 4]>> {
    let mut reader = csv::Reader::from_reader(UNCERTAIN.as_bytes());
    let mut out = vec![];
    for r in reader.records() {
        let r = r.context("reports/papers/uncertain.csv")?;
        out.push(std::array::from_fn(|i| r.get(i).unwrap_or("").to_string()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_paper_csv_parses_with_its_rows() {
        let expected_rows = [
            ("havs_table1", 4),
            ("havs_table2", 5),
            ("havs_table3", 5),
            ("havs_table4", 5),
            ("havs_table5", 5),
            ("gator_table1", 14),
            ("gator_table2", 3),
            ("gator_table3", 3),
            ("fragment-pt_table1", 7),
            ("fragment-pt_table2", 5),
            ("raycast_table3", 6),
            ("raycast_table4", 3),
            ("raycast_table5", 6),
            ("raycast_table6", 6),
            ("splat_table1", 6),
        ];
        assert_eq!(expected_rows.len(), CSVS.len());
        for (name, n) in expected_rows {
            let t = table(name).unwrap();
            assert_eq!(t.rows.len(), n, "{name}");
            assert!(t.rows.iter().all(|r| r.len() == t.header.len()), "{name}");
        }
        let t3 = table("havs_table3").unwrap();
        assert_eq!(t3.value("spx2", "k2_fps"), Some(2.07));
        assert_eq!(t3.value("torso", "cells"), Some(1_082_723.0));
        let rc = table("raycast_table5").unwrap();
        assert_eq!(
            rc.value("ATI 9700 Pro / spx1", "tiles_5x5_max_ms"),
            Some(750.0)
        );
        assert_eq!(rc.value("GeForce 6800 GT / f117", "tiles_1x1_min_ms"), None);
        assert!(rc
            .uncertain("GeForce 6800 GT / f117", "tiles_1x1_min_ms")
            .is_some());
    }

    #[test]
    fn uncertain_cells_name_existing_rows_and_columns() {
        for [paper, table_id, row, column] in uncertain_cells().unwrap() {
            let t = table(&format!("{paper}_{table_id}")).unwrap();
            assert!(
                row == "*" || t.keys().contains(&row),
                "{paper} {table_id} {row}"
            );
            assert!(
                column == "*" || t.header.contains(&column),
                "{paper} {table_id} {column}"
            );
        }
    }
}
