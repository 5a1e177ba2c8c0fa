//! A row as `results.csv` holds it: one flat line with the typed maps (settings, stages,
//! counters) as their text, and without what `results.json` alone keeps (the per-frame
//! samples, the rounds' control).
//!
//! [`CsvRow`] is that view of a [`Row`], taken where the CSV is written. It runs the row's own
//! derived `Serialize` through a serializer that swaps those columns as they go by, so the
//! column list and order come from `Row` alone, the JSON form of the same row is untouched,
//! and nothing outside the call decides which form is written.

use serde::ser::{self, Impossible, Serialize, SerializeStruct, Serializer};

use crate::results::Row;

/// The CSV view of a row: serialise this, not the row, into a `csv::Writer`.
pub struct CsvRow<'a>(pub &'a Row);

impl Serialize for CsvRow<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(Flat {
            inner: s,
            row: self.0,
        })
    }
}

/// How the CSV writes one of the row's columns.
enum Column {
    /// As this text (a map in the JSON).
    Text(String),
    /// Not at all (JSON only).
    Left,
    /// As the JSON does.
    Same,
}

fn column(row: &Row, key: &str) -> Column {
    match key {
        "settings" => Column::Text(row.settings.to_string()),
        "stages" => Column::Text(row.stages.to_string()),
        "counters" => Column::Text(row.counters.to_string()),
        "samples" | "round_control" => Column::Left,
        _ => Column::Same,
    }
}

/// The serializer a [`Row`] meets inside [`CsvRow`]: a struct's fields pass to `inner`,
/// swapped by [`column`]; a row is a struct, so nothing else is expected.
struct Flat<'a, S> {
    inner: S,
    row: &'a Row,
}

struct FlatFields<'a, S> {
    inner: S,
    row: &'a Row,
}

impl<S: SerializeStruct> SerializeStruct for FlatFields<'_, S> {
    type Ok = S::Ok;
    type Error = S::Error;

    fn serialize_field<T: ?Sized + Serialize>(
        &mut self,
        key: &'static str,
        value: &T,
    ) -> Result<(), S::Error> {
        match column(self.row, key) {
            Column::Text(text) => self.inner.serialize_field(key, &text),
            Column::Left => self.inner.skip_field(key),
            Column::Same => self.inner.serialize_field(key, value),
        }
    }

    fn skip_field(&mut self, key: &'static str) -> Result<(), S::Error> {
        self.inner.skip_field(key)
    }

    fn end(self) -> Result<S::Ok, S::Error> {
        self.inner.end()
    }
}

fn not_a_row<E: ser::Error>() -> E {
    E::custom("the CSV view serialises a results row, which is a struct")
}

/// Every serializer method but `serialize_struct`: refused.
macro_rules! refuse {
    ($($method:ident($($arg:ty),*) -> $ret:ty;)*) => {$(
        fn $method(self, $(_: $arg),*) -> Result<$ret, S::Error> {
            Err(not_a_row())
        }
    )*};
}

impl<'a, S: Serializer> Serializer for Flat<'a, S> {
    type Ok = S::Ok;
    type Error = S::Error;
    type SerializeSeq = Impossible<S::Ok, S::Error>;
    type SerializeTuple = Impossible<S::Ok, S::Error>;
    type SerializeTupleStruct = Impossible<S::Ok, S::Error>;
    type SerializeTupleVariant = Impossible<S::Ok, S::Error>;
    type SerializeMap = Impossible<S::Ok, S::Error>;
    type SerializeStruct = FlatFields<'a, S::SerializeStruct>;
    type SerializeStructVariant = Impossible<S::Ok, S::Error>;

    fn serialize_struct(
        self,
        name: &'static str,
        len: usize,
    ) -> Result<Self::SerializeStruct, S::Error> {
        Ok(FlatFields {
            inner: self.inner.serialize_struct(name, len)?,
            row: self.row,
        })
    }

    refuse! {
        serialize_bool(bool) -> S::Ok;
        serialize_i8(i8) -> S::Ok;
        serialize_i16(i16) -> S::Ok;
        serialize_i32(i32) -> S::Ok;
        serialize_i64(i64) -> S::Ok;
        serialize_u8(u8) -> S::Ok;
        serialize_u16(u16) -> S::Ok;
        serialize_u32(u32) -> S::Ok;
        serialize_u64(u64) -> S::Ok;
        serialize_f32(f32) -> S::Ok;
        serialize_f64(f64) -> S::Ok;
        serialize_char(char) -> S::Ok;
        serialize_str(&str) -> S::Ok;
        serialize_bytes(&[u8]) -> S::Ok;
        serialize_none() -> S::Ok;
        serialize_unit() -> S::Ok;
        serialize_unit_struct(&'static str) -> S::Ok;
        serialize_unit_variant(&'static str, u32, &'static str) -> S::Ok;
        serialize_seq(Option<usize>) -> Self::SerializeSeq;
        serialize_tuple(usize) -> Self::SerializeTuple;
        serialize_tuple_struct(&'static str, usize) -> Self::SerializeTupleStruct;
        serialize_tuple_variant(&'static str, u32, &'static str, usize)
            -> Self::SerializeTupleVariant;
        serialize_map(Option<usize>) -> Self::SerializeMap;
        serialize_struct_variant(&'static str, u32, &'static str, usize)
            -> Self::SerializeStructVariant;
    }

    fn serialize_some<T: ?Sized + Serialize>(self, _: &T) -> Result<S::Ok, S::Error> {
        Err(not_a_row())
    }

    fn serialize_newtype_struct<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        _: &T,
    ) -> Result<S::Ok, S::Error> {
        Err(not_a_row())
    }

    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<S::Ok, S::Error> {
        Err(not_a_row())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::{test_row, FrameSamples};

    /// The same row: maps in JSON, text in the CSV, and the per-frame parts only in JSON.
    #[test]
    fn one_row_is_maps_in_json_and_text_in_csv() {
        let mut row = test_row(0);
        row.stages = "sort=1.5;draw=3".into();
        row.samples = FrameSamples {
            total_ms: vec![2.0],
            cpu_ms: vec![1.0],
            ..FrameSamples::default()
        };
        let json = serde_json::to_string(&row).unwrap();
        assert!(
            json.contains(r#""stages":{"sort":1.5,"draw":3.0}"#),
            "{json}"
        );
        assert!(
            json.contains(r#""settings":{"variant":"a","sort":"radix"}"#),
            "{json}"
        );
        assert!(json.contains(r#""samples""#));
        let mut w = csv::Writer::from_writer(vec![]);
        w.serialize(CsvRow(&row)).unwrap();
        let csv = String::from_utf8(w.into_inner().unwrap()).unwrap();
        assert!(csv.contains(",sort=1.5000;draw=3,"), "{csv}");
        assert!(csv.contains(",variant=a;sort=radix,"), "{csv}");
        assert!(!csv.contains("samples"), "{csv}");
        // Serialising the CSV view leaves the JSON form as it was.
        assert_eq!(serde_json::to_string(&row).unwrap(), json);
        let back: Row = csv::Reader::from_reader(csv.as_bytes())
            .deserialize()
            .next()
            .unwrap()
            .unwrap();
        assert_eq!(back.stages, row.stages);
    }

    /// Real rows (a committed baseline's, suspect and bound rows among them) written, read
    /// back from either file and written again are the same rows and the same bytes.
    #[test]
    fn written_rows_read_back_equal_and_write_the_same_bytes() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../reports/baselines/llvmpipe-llvm-15-0-6-256-bits-2026-12-03");
        let file = crate::results::ResultsFile::read(&dir).unwrap();
        assert!(file.rows.iter().any(|r| r.suspect.is_some()));
        assert!(file.rows.iter().any(|r| r.bound_by.is_some()));
        let write = |file: &crate::results::ResultsFile| {
            let tmp = tempfile::tempdir().unwrap();
            crate::results::write_csv(tmp.path(), &file.rows).unwrap();
            crate::results::write_json(tmp.path(), file).unwrap();
            tmp
        };
        let first = write(&file);
        let again = crate::results::ResultsFile::read(first.path()).unwrap();
        assert_eq!(again, file);
        let mut csv = csv::Reader::from_path(first.path().join(crate::results::CSV_FILE)).unwrap();
        let from_csv: Vec<Row> = csv.deserialize().collect::<Result<_, _>>().unwrap();
        let flat = |r: &Row| {
            (
                r.settings.to_string(),
                r.suspect.clone(),
                r.bound_by,
                r.error.clone(),
            )
        };
        assert!(from_csv.iter().map(flat).eq(file.rows.iter().map(flat)));
        let second = write(&again);
        for name in [crate::results::JSON_FILE, crate::results::CSV_FILE] {
            let read = |d: &tempfile::TempDir| std::fs::read(d.path().join(name)).unwrap();
            assert!(
                read(&first) == read(&second),
                "{name} differs when written again"
            );
        }
    }
}
