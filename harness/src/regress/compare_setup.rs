//! What a comparison is set up with: the options of `tetbench compare` (and of `ab`,
//! `bisect`, `history`, which judge with it), the exit status of a met gate, and the key that
//! matches a row of BASE with its row in NEW. The lowest layer of compare's modules: it imports
//! none of them.

use render_core::Settings;
use std::path::PathBuf;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::results::Row;

/// `compare --fail-on` met: the exit status, distinct from 1 (an error, or a comparison
/// refused: other adapters, unreadable results) so that CI can tell a regression from a
/// broken job.
pub const EXIT_REGRESSION: i32 = 3;

#[derive(
    Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum FailOn {
    /// Always exit 0 (the report is the product).
    Never,
    /// Exit 3 when anything got slower, less exact, bigger, did more work, or failed.
    Regression,
    /// Exit 3 on any change at all, including improvements and changed pixels.
    Change,
}

#[derive(Debug, Clone)]
pub struct CompareOptions {
    pub threshold: f64,
    pub alpha: f64,
    pub normalised: bool,
    /// Divide NEW's times by the run-wide factor before testing ([`run_wide_factor`]).
    pub drift_correction: bool,
    /// A run-wide factor beyond this is a regression (or improvement) of its own.
    pub drift_limit: f64,
    /// BASE's round i and NEW's round i ran side by side (`tetbench ab`): with drift
    /// correction, each pair's own factor is divided out ([`pair_factors`]) instead of the
    /// run-wide one.
    pub paired: bool,
    pub fail_on: FailOn,
    pub out: PathBuf,
}

/// A row's place in the matrix: algorithm, settings, data set, viewpoint, viewport.
pub type Key = (String, Settings, String, String, u32, u32);

pub fn key(r: &Row) -> Key {
    (
        r.algorithm.clone(),
        r.settings.clone(),
        r.dataset.clone(),
        r.viewpoint.clone(),
        r.width,
        r.height,
    )
}
