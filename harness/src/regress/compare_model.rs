//! What a comparison found, as `compare.json` holds it: each row's and group's outcome, the
//! findings, and the comparison as a whole. Types only (and their small methods): the driver
//! that fills them is [`crate::regress::compare`].

use render_core::Settings;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::regress::compare_image::ImageChange;
use crate::regress::compare_rounds::{GroupComparison, Rounds};
use crate::regress::compare_time::TimeTest;
use crate::regress::compare_work::WorkChange;
use crate::results::description::as_text;

/// The layout of `compare.json` (`docs/compare.schema.json`); bumped when a field changes
/// meaning or is removed.
pub const SCHEMA_VERSION: u32 = 1;

/// What became of one row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub enum RowStatus {
    /// Slower, less exact, more work or bytes, or fails now.
    #[serde(rename = "regression")]
    Regression,
    #[serde(rename = "improvement")]
    Improvement,
    /// Changed pixels or a counter only one side reports, neither better nor worse.
    #[serde(rename = "changed")]
    Changed,
    #[serde(rename = "no change")]
    NoChange,
    #[serde(rename = "only in base")]
    OnlyInBase,
    #[serde(rename = "only in new")]
    OnlyInNew,
}

impl RowStatus {
    pub fn label(self) -> &'static str {
        match self {
            RowStatus::Regression => "regression",
            RowStatus::Improvement => "improvement",
            RowStatus::Changed => "changed",
            RowStatus::NoChange => "no change",
            RowStatus::OnlyInBase => "only in base",
            RowStatus::OnlyInNew => "only in new",
        }
    }
}

impl std::fmt::Display for RowStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RowComparison {
    pub algorithm: String,
    #[serde(serialize_with = "as_text")]
    #[schemars(with = "String")]
    pub settings: Settings,
    pub dataset: String,
    pub viewpoint: String,
    pub width: u32,
    pub height: u32,
    pub status: RowStatus,
    pub notes: Vec<String>,
    pub times: Vec<TimeTest>,
    pub image: Option<ImageChange>,
    /// Every work counter and GPU byte figure that differs ([`crate::regress::compare_work`]).
    pub work: Vec<WorkChange>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Comparison {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    pub base: String,
    pub new: String,
    pub base_adapter: String,
    pub new_adapter: String,
    pub base_commit: Option<String>,
    pub new_commit: Option<String>,
    pub normalised: bool,
    pub threshold: f64,
    pub alpha: f64,
    /// Rounds per row on each side; time is judged only with [`MIN_ROUNDS`] or more on both.
    pub rounds: Rounds,
    /// What makes the comparison less trustworthy: a side built from a dirty tree or as a
    /// debug build ([`provenance_warnings`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Why time was not judged, when it was not (too few rounds, or too noisy).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_refused: Option<String>,
    /// Separate runs too noisy to gate on time ([`time_noise`]): the spread of the groups'
    /// ratios around the run-wide factor, as a factor (`None`: not estimated).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub group_spread: Option<f64>,
    pub too_noisy: bool,
    /// NEW / BASE over the whole run: the median of the groups' pooled `total_ms` ratios
    /// (`None`: too few groups), after the machine was divided out where both runs have a
    /// control (`machine`). When `drift_corrected`, every NEW time was divided by it before
    /// the tests, so a group is judged against the rest of its own run (the old rule).
    pub run_factor: Option<f64>,
    /// The machine's drift between the runs, from the control measured beside the rows: every
    /// round value of both sides was divided by it before the tests.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub machine: Option<crate::regress::compare_control::MachineDrift>,
    /// Two machines (adapters, or hosts of one adapter), both with a control: each group's raw
    /// ratio beside its control-normalised one, as information.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub across: Option<crate::regress::compare_across::AcrossMachines>,
    /// Why the run-wide factor stood in for the control (a side without one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub control_missing: Option<String>,
    pub drift_corrected: bool,
    /// With paired rounds (`ab`): each pair's NEW/BASE factor, divided out of that pair's
    /// NEW round values instead of `run_factor`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pair_factors: Option<Vec<f64>>,
    pub test: String,
    pub groups: Vec<GroupComparison>,
    pub rows: Vec<RowComparison>,
    pub regressions: Vec<Finding>,
    pub improvements: Vec<Finding>,
    pub changes: Vec<Finding>,
}

impl Comparison {
    /// One word for the whole comparison.
    /// Two adapters compared without `--normalised`: printed, never a gate.
    pub fn information_only(&self) -> bool {
        self.across.as_ref().is_some_and(|a| a.information_only)
    }

    pub fn outcome(&self) -> &'static str {
        if self.information_only() {
            "information only"
        } else if !self.regressions.is_empty() {
            "regression"
        } else if !self.improvements.is_empty() || !self.changes.is_empty() {
            "changed"
        } else {
            "no change"
        }
    }
}

/// The JSON Schema of `compare.json` (`docs/compare.schema.json`).
pub fn json_schema() -> serde_json::Value {
    serde_json::to_value(schemars::schema_for!(Comparison)).expect("a schema is JSON")
}

/// Which way a finding goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum FindingVerdict {
    /// Time: the group (or row, or the whole run) got slower / faster.
    Slower,
    Faster,
    /// Work: a counter or byte figure grew / shrank (exact).
    More,
    Less,
    /// A counter only one side reports.
    Added,
    Removed,
    /// Image: PSNR dropped / rose beyond the tolerance, or the pixels changed.
    Worse,
    Better,
    Changed,
    /// The row failed in NEW only / in BASE only.
    FailsNow,
    NoLongerFails,
    /// The row exists on one side only.
    OnlyInBase,
    OnlyInNew,
}

/// One regression, improvement or other change.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Finding {
    /// `algorithm settings on dataset` (the group), or `run-wide` for the run as a whole.
    pub group: String,
    /// The row's viewpoint; `None` for a group's pooled test or the run-wide factor.
    pub viewpoint: Option<String>,
    /// What moved: `total_ms`, a counter (`fragments`), a byte figure (`gpu_bytes`), `image`,
    /// `error`, `row`.
    pub metric: String,
    /// NEW / BASE, where there is one.
    pub ratio: Option<f64>,
    /// The test's p-value (time only) and the Holm-adjusted one that decided.
    pub p: Option<f64>,
    pub p_holm: Option<f64>,
    pub verdict: FindingVerdict,
    /// The finding as the reports print it.
    pub text: String,
}
