//! A registry entry (one named data set as listed by `tetbench datasets`), in its own module so
//! that the modules contributing entries (`standins`) need not import the registry.

/// One named data set.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Entry {
    pub name: String,
    pub description: String,
    /// Files it needs, relative to the data directory (empty for generators).
    pub files: Vec<String>,
    /// All files present (always true for generators).
    pub present: bool,
    /// Which papers used it / what it stands in for.
    pub paper: &'static str,
}
