//! `tetbench compare BASE NEW`: did NEW get slower, less exact or bigger than BASE, beyond noise?
//!
//! Rows are matched by (algorithm, settings, data set, viewpoint, size). Per row:
//! - **time** (`total_ms`, `cpu_ms`, `gpu_ms`): the Mann–Whitney U test plus asv's factor
//!   threshold ([`crate::results::stats`] says why): "slower" needs the ratio of medians ≥ threshold
//!   *and* p < α. The unit of replication is the **round** (`run --rounds`), not the frame:
//!   frames rendered back to back share the machine's state of that moment, so they are one
//!   sample, and testing them as many is pseudo-replication (any drift during one round
//!   becomes "significant"). Each row contributes one value per round (the median of that
//!   round's frames, [`round_values`]); with fewer than [`MIN_ROUNDS`] rounds on either side
//!   every time verdict is "too few independent samples (N rounds)" and time never gates
//!   (image and memory still do: they are exact). A single row (3 vs 3 rounds in the default
//!   suite) cannot reach p < 0.05 (the smallest exact p of 3 vs 3 is 0.1), so the decision
//!   that gates is the **group** test: per algorithm × settings × data set, every viewpoint's
//!   round values divided by BASE's median of that viewpoint, pooled (9 vs 9 in the default
//!   suite).
//!   Only `total_ms` gates; CPU and GPU ms are reported (a GPU-resident variant's 0.05 ms of CPU
//!   time moves by 10 % with nothing changed).
//! - **image**: rendering is deterministic on one adapter, so any changed f32 pixel is reported
//!   (hash of the pixels; with both images present the changed-pixel count, largest difference
//!   and a heatmap), as is any PSNR change > 0.1 dB; a PSNR drop > 0.1 dB is a regression.
//! - **memory**: any change of GPU bytes; an increase is a regression.
//!
//! Runs on different adapters are refused unless `--normalised`: then every sample is divided
//! by its row's roofline time (from that machine's calibration, [`crate::calibrate`]), images
//! are not compared pixel by pixel (adapters legitimately differ), and every output says so.

use render_core::Settings;
use std::path::{Path, PathBuf};

use anyhow::Context;
use serde::{Deserialize, Serialize};

pub use crate::regress::compare_time::{
    adjust_family, fmt_p, pair_factors, paired_t_tests, run_wide_factor, scaled, time_test,
    TimeTest, Verdict, MIN_GROUPS_FOR_DRIFT,
};
use crate::results::aggregate::GroupKey;
use crate::results::samples;
use crate::results::stats::{holm_adjust, mann_whitney_p, median};
use crate::results::{ResultsFile, Row};

/// A PSNR change larger than this is reported (and a drop this large is a regression).
pub const PSNR_TOLERANCE_DB: f64 = 0.1;

/// Fewer rounds than this on either side and time is not judged: 2 vs 2 values cannot reach
/// p < 0.05 even pooled over a few viewpoints, and one round is one moment of the machine.
pub const MIN_ROUNDS: u32 = 3;

/// How many independent samples (rounds) each side's rows hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Rounds {
    pub base: u32,
    pub new: u32,
}

impl Rounds {
    pub fn of(base: &ResultsFile, new: &ResultsFile) -> Rounds {
        Rounds {
            base: base.run.rounds.max(1),
            new: new.run.rounds.max(1),
        }
    }

    /// Whether time may be judged at all.
    pub fn enough(self) -> bool {
        self.base.min(self.new) >= MIN_ROUNDS
    }

    /// Why time is not judged (`None`: it is).
    pub fn refusal(self) -> Option<String> {
        (!self.enough()).then(|| {
            format!(
                "time: too few independent samples ({} rounds; BASE {}, NEW {}): frames of one \
                 round are one sample, so no time verdict and no time gate; run both sides with \
                 --rounds {MIN_ROUNDS} or more",
                self.base.min(self.new),
                self.base,
                self.new
            )
        })
    }
}

impl Default for Rounds {
    fn default() -> Self {
        Rounds { base: 1, new: 1 }
    }
}

/// `compare --fail-on` met: the exit status, distinct from 1 (an error, or a comparison
/// refused: other adapters, unreadable results) so that CI can tell a regression from a
/// broken job.
pub const EXIT_REGRESSION: i32 = 3;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FailOn {
    /// Always exit 0 (the report is the product).
    Never,
    /// Exit 3 when anything got slower, less exact, bigger, or failed.
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

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImageChange {
    pub psnr_base_db: Option<f64>,
    pub psnr_new_db: Option<f64>,
    pub psnr_delta_db: Option<f64>,
    /// Whether the pixels' hashes differ (`None`: a side has no hash, or --normalised).
    pub pixels_changed: Option<bool>,
    /// With both f32 images at hand: pixels with any channel changed, largest difference, and
    /// the heatmap of the difference (relative to the compare output directory).
    pub changed_pixels: Option<u64>,
    pub max_abs_difference: Option<f64>,
    pub heatmap: String,
    /// `same`, `changed`, `better` or `worse`.
    pub verdict: String,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MemoryChange {
    pub what: String,
    pub base: u64,
    pub new: u64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RowComparison {
    pub algorithm: String,
    pub settings: String,
    pub dataset: String,
    pub viewpoint: String,
    pub width: u32,
    pub height: u32,
    /// `regression`, `improvement`, `changed`, `no change`, `only in base`, `only in new`.
    pub status: String,
    pub notes: Vec<String>,
    pub times: Vec<TimeTest>,
    pub image: Option<ImageChange>,
    pub memory: Vec<MemoryChange>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroupComparison {
    pub algorithm: String,
    pub settings: String,
    pub dataset: String,
    /// The group's viewport ([`GroupKey`]): one variant at two sizes is two groups.
    #[serde(default)]
    pub width: u32,
    #[serde(default)]
    pub height: u32,
    #[serde(default)]
    pub projection: String,
    pub viewpoints: usize,
    /// Pooled `total_ms` test over the viewpoints.
    pub total: TimeTest,
}

impl GroupComparison {
    /// Whether this is the comparison of the reports' group `g`.
    pub fn is(&self, g: &GroupKey) -> bool {
        (&self.algorithm, &self.settings, &self.dataset)
            == (&g.algorithm, &g.settings.to_string(), &g.dataset)
            && (self.width, self.height, &self.projection) == (g.width, g.height, &g.projection)
    }
}

impl RowComparison {
    /// Whether the row belongs to group `g` (a row comparison keeps no projection: matched on
    /// the rest).
    pub fn in_group(&self, g: &GroupKey) -> bool {
        (&self.algorithm, &self.settings, &self.dataset)
            == (&g.algorithm, &g.settings.to_string(), &g.dataset)
            && (self.width, self.height) == (g.width, g.height)
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
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
    #[serde(default)]
    pub rounds: Rounds,
    /// What makes the comparison less trustworthy: a side built from a dirty tree or as a
    /// debug build ([`provenance_warnings`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Why time was not judged, when it was not ([`Rounds::refusal`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_refused: Option<String>,
    /// NEW / BASE over the whole run: the median of the groups' pooled `total_ms` ratios
    /// (`None`: too few groups). When `drift_corrected`, every NEW time was divided by it
    /// before the tests, so a group is judged against the rest of its own run.
    #[serde(default)]
    pub run_factor: Option<f64>,
    #[serde(default)]
    pub drift_corrected: bool,
    /// With paired rounds (`ab`): each pair's NEW/BASE factor, divided out of that pair's
    /// NEW round values instead of `run_factor`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pair_factors: Option<Vec<f64>>,
    pub test: String,
    pub groups: Vec<GroupComparison>,
    pub rows: Vec<RowComparison>,
    pub regressions: Vec<String>,
    pub improvements: Vec<String>,
    pub changes: Vec<String>,
}

impl Comparison {
    /// One word for the whole comparison.
    pub fn outcome(&self) -> &'static str {
        if !self.regressions.is_empty() {
            "regression"
        } else if !self.improvements.is_empty() || !self.changes.is_empty() {
            "changed"
        } else {
            "no change"
        }
    }
}

/// The adapter a results set ran on, as compare matches them (a software rasteriser with its CPU).
pub fn adapter_of(f: &ResultsFile) -> String {
    let Some(a) = f.machine.adapter.as_ref() else {
        return "unknown adapter".into();
    };
    let name = format!("{} ({} {})", a.name, a.driver, a.driver_info)
        .trim()
        .to_string();
    // A software rasteriser (lavapipe, WARP, SwiftShader) runs on the CPU, which is then the
    // GPU: one name on two CPUs is two different devices.
    if a.device_type.eq_ignore_ascii_case("cpu") {
        format!("{name} on {}", f.machine.cpu_model)
    } else {
        name
    }
}

/// A row's place in the matrix: algorithm, settings, data set, viewpoint, viewport.
pub(crate) type Key = (String, Settings, String, String, u32, u32);

pub(crate) fn key(r: &Row) -> Key {
    (
        r.algorithm.clone(),
        r.settings.clone(),
        r.dataset.clone(),
        r.viewpoint.clone(),
        r.width,
        r.height,
    )
}

/// The samples of `metric`, divided by the row's roofline time when normalising.
fn metric_samples(r: &Row, metric: &str, normalised: bool) -> anyhow::Result<Vec<f64>> {
    let s = r.samples.metric(metric);
    if !normalised || s.is_empty() {
        return Ok(s.to_vec());
    }
    let roof = r.roofline_ms.filter(|t| *t > 0.0).ok_or_else(|| {
        anyhow::anyhow!(
            "--normalised: row {} {} {} {} has no roofline (was the run calibrated?)",
            r.algorithm,
            r.settings,
            r.dataset,
            r.viewpoint
        )
    })?;
    Ok(s.iter().map(|x| x / roof).collect())
}

/// One value per round of `metric` (the median of that round's frames), divided by the row's
/// roofline time when normalising. A row's samples hold its rounds one after the other
/// (`run::DatasetContext::run_variants`); samples that do not split evenly into `rounds`
/// (a round failed) give one value, which decides nothing.
pub fn round_values(
    r: &Row,
    metric: &str,
    rounds: u32,
    normalised: bool,
) -> anyhow::Result<Vec<f64>> {
    let s = metric_samples(r, metric, normalised)?;
    let rounds = rounds.max(1) as usize;
    if s.is_empty() {
        return Ok(s);
    }
    if s.len() % rounds != 0 {
        return Ok(vec![median(&s)]);
    }
    Ok(s.chunks(s.len() / rounds).map(median).collect())
}

/// [`time_test`], with the verdict withheld when the runs have too few rounds.
fn round_test(
    metric: &str,
    base: &[f64],
    new: &[f64],
    opt: &CompareOptions,
    rounds: Rounds,
) -> TimeTest {
    let mut t = time_test(metric, base, new, opt.threshold, opt.alpha);
    if !rounds.enough() {
        t.verdict = Verdict::TooFewSamples;
    }
    t
}

/// Compares two result directories; writes nothing (see [`write_outputs`]).
pub fn compare(
    base_dir: &Path,
    new_dir: &Path,
    opt: &CompareOptions,
) -> anyhow::Result<Comparison> {
    let base = ResultsFile::read(base_dir)?;
    let new = ResultsFile::read(new_dir)?;
    let (ba, na) = (adapter_of(&base), adapter_of(&new));
    if ba != na && !opt.normalised {
        anyhow::bail!(
            "{} ran on {ba} but {} on {na}: times from two adapters say nothing about a change. \
             Pass --normalised to compare calibration-normalised figures instead",
            base_dir.display(),
            new_dir.display()
        );
    }
    if opt.normalised {
        for (f, d) in [(&base, base_dir), (&new, new_dir)] {
            anyhow::ensure!(
                f.machine.calibration.is_some(),
                "--normalised: {} has no calibration in its machine record (run it without \
                 --no-calibrate)",
                d.display()
            );
        }
    }
    let heat_dir = opt.out.join("heatmaps");
    let rounds = Rounds::of(&base, &new);
    let unscaled = group_tests(&base.rows, &new.rows, opt, &[1.0], rounds)?;
    let run_factor = run_wide_factor(unscaled.iter().map(|g| &g.total));
    let pair_factors = (opt.paired && opt.drift_correction && rounds.base == rounds.new)
        .then(|| pair_factors(&group_pair_ratios(&base.rows, &new.rows, rounds, opt).ok()?))
        .flatten();
    let scale: Vec<f64> = match (&pair_factors, run_factor) {
        (Some(per_pair), _) => per_pair.clone(),
        (None, Some(f)) if opt.drift_correction => vec![f],
        _ => vec![1.0],
    };
    let pairs: Vec<(&Row, Option<&Row>)> = base
        .rows
        .iter()
        .map(|b| (b, new.rows.iter().find(|n| key(n) == key(b))))
        .collect();
    // The rows' total_ms tests are one family (Holm): their adjusted p decides each row.
    let mut raw_total_p = vec![];
    for (b, n) in &pairs {
        raw_total_p.push(match n {
            Some(n) => {
                let bs = round_values(b, "total_ms", rounds.base, opt.normalised)?;
                let ns = scaled(
                    round_values(n, "total_ms", rounds.new, opt.normalised)?,
                    &scale,
                );
                (rounds.enough() && bs.len() >= 2 && ns.len() >= 2)
                    .then(|| mann_whitney_p(&bs, &ns))
                    .flatten()
            }
            None => None,
        });
    }
    let mut rows = vec![];
    for ((b, n), p_total) in pairs.into_iter().zip(holm_adjust(&raw_total_p)) {
        rows.push(match n {
            Some(n) => compare_rows(
                b,
                n,
                (p_total, &scale, rounds),
                (base_dir, new_dir, &heat_dir),
                opt,
            )?,
            None => only(b, "only in base"),
        });
    }
    for n in &new.rows {
        if !base.rows.iter().any(|b| key(b) == key(n)) {
            rows.push(only(n, "only in new"));
        }
    }
    let mut groups = group_tests(&base.rows, &new.rows, opt, &scale, rounds)?;
    adjust_family(
        groups.iter_mut().map(|g| &mut g.total),
        opt.threshold,
        opt.alpha,
    );
    let mut cmp = Comparison {
        base: base_dir.display().to_string(),
        new: new_dir.display().to_string(),
        base_adapter: ba,
        new_adapter: na,
        base_commit: base.machine.git_commit.clone(),
        new_commit: new.machine.git_commit.clone(),
        normalised: opt.normalised,
        threshold: opt.threshold,
        alpha: opt.alpha,
        rounds,
        warnings: [("BASE", &base), ("NEW", &new)]
            .iter()
            .flat_map(|(side, f)| provenance_warnings(side, f))
            .collect(),
        time_refused: rounds.refusal(),
        run_factor,
        drift_corrected: scale != [1.0],
        pair_factors,
        test: format!(
            "Mann–Whitney U (two-sided, α = {}, Holm-adjusted over the groups and over the \
             rows) and ratio of medians ≥ {} (asv's rule){}",
            opt.alpha,
            opt.threshold,
            if scale.len() > 1 {
                "; groups (paired rounds): a t-test of each group's per-pair ln(NEW/BASE), each \
                 pair's drift divided out, variance pooled over the groups; ratio = exp(mean)"
            } else {
                ""
            }
        ),
        groups,
        rows,
        regressions: vec![],
        improvements: vec![],
        changes: vec![],
    };
    if let Some(f) = run_factor {
        let what = format!(
            "run-wide: every group's total_ms ×{f:.3} (median over {} groups; machine drift or \
             a change common to all algorithms, beyond --drift-limit {})",
            cmp.groups.len(),
            opt.drift_limit
        );
        if f >= opt.drift_limit {
            cmp.regressions.push(what);
        } else if f <= 1.0 / opt.drift_limit {
            cmp.improvements.push(what);
        }
    }
    for g in &cmp.groups {
        let name = format!(
            "{} {} on {}: total_ms ×{:.3} (p = {})",
            g.algorithm,
            g.settings,
            g.dataset,
            g.total.ratio,
            g.total.p_label()
        );
        match g.total.verdict {
            Verdict::Slower => cmp.regressions.push(format!("slower: {name}")),
            Verdict::Faster => cmp.improvements.push(format!("faster: {name}")),
            _ => {}
        }
    }
    for r in &cmp.rows {
        let name = format!(
            "{} {} {} {}: {}",
            r.algorithm,
            r.settings,
            r.dataset,
            r.viewpoint,
            r.notes.join("; ")
        );
        match r.status.as_str() {
            "regression" => cmp.regressions.push(name),
            "improvement" => cmp.improvements.push(name),
            "no change" => {}
            _ => cmp.changes.push(name),
        }
    }
    Ok(cmp)
}

/// Why one side's numbers may not be what its commit does: built from a dirty tree (the commit
/// is not the code), or a debug build (times of another program).
pub fn provenance_warnings(side: &str, f: &ResultsFile) -> Vec<String> {
    let m = &f.machine;
    let mut out = vec![];
    if m.git_dirty == Some(true) {
        out.push(format!(
            "{side} was built from a dirty tree (commit {} plus uncommitted changes)",
            m.git_commit.as_deref().unwrap_or("?")
        ));
    }
    if m.build_profile.as_deref() == Some("debug") {
        out.push(format!(
            "{side} is a debug build: its times are not those of a release build"
        ));
    }
    out
}

fn only(r: &Row, status: &str) -> RowComparison {
    RowComparison {
        algorithm: r.algorithm.clone(),
        settings: r.settings.to_string(),
        dataset: r.dataset.clone(),
        viewpoint: r.viewpoint.clone(),
        width: r.width,
        height: r.height,
        status: status.to_string(),
        notes: vec![status.to_string()],
        times: vec![],
        image: None,
        memory: vec![],
    }
}

/// One matched row. `time`: the Holm-adjusted p of its `total_ms`, the run-wide factor NEW is
/// divided by, and the rounds; `dirs`: BASE, NEW and where heatmaps go.
fn compare_rows(
    b: &Row,
    n: &Row,
    time: (Option<f64>, &[f64], Rounds),
    dirs: (&Path, &Path, &Path),
    opt: &CompareOptions,
) -> anyhow::Result<RowComparison> {
    let (total_p_adjusted, scale, rounds) = time;
    let (base_dir, new_dir, heat_dir) = dirs;
    let mut out = only(b, "no change");
    out.notes.clear();
    let (mut worse, mut better, mut changed) = (false, false, false);
    match (b.ok(), n.ok()) {
        (true, false) => {
            worse = true;
            out.notes.push(format!("failed now: {}", n.error));
        }
        (false, true) => {
            better = true;
            out.notes.push("no longer fails".into());
        }
        (false, false) => out.notes.push("fails in both".into()),
        (true, true) => {}
    }
    for metric in ["total_ms", "cpu_ms", "gpu_ms"] {
        let (bs, mut ns) = (
            round_values(b, metric, rounds.base, opt.normalised)?,
            round_values(n, metric, rounds.new, opt.normalised)?,
        );
        if bs.is_empty() && ns.is_empty() {
            continue;
        }
        if metric == "total_ms" {
            ns = scaled(ns, scale);
        }
        let mut t = round_test(metric, &bs, &ns, opt, rounds);
        if metric == "total_ms" {
            t = t.with_family_p(total_p_adjusted, opt.threshold, opt.alpha);
            match t.verdict {
                Verdict::Slower => {
                    worse = true;
                    out.notes.push(format!("slower ×{:.3}", t.ratio));
                }
                Verdict::Faster => {
                    better = true;
                    out.notes.push(format!("faster ×{:.3}", t.ratio));
                }
                _ => {}
            }
        }
        out.times.push(t);
    }
    let img = image_change(b, n, base_dir, new_dir, heat_dir, opt)?;
    match img.verdict.as_str() {
        "worse" => worse = true,
        "better" => better = true,
        "changed" => changed = true,
        _ => {}
    }
    if img.verdict != "same" {
        out.notes.push(image_note(&img));
    }
    out.image = Some(img);
    for (what, bv, nv) in [
        ("gpu_bytes", b.gpu_bytes, n.gpu_bytes),
        (
            "gpu_bytes_persistent",
            b.gpu_bytes_persistent,
            n.gpu_bytes_persistent,
        ),
        ("gpu_bytes_frame", b.gpu_bytes_frame, n.gpu_bytes_frame),
    ] {
        if let (Some(bv), Some(nv)) = (bv, nv) {
            if bv != nv {
                out.memory.push(MemoryChange {
                    what: what.into(),
                    base: bv,
                    new: nv,
                });
                if what == "gpu_bytes" {
                    out.notes.push(format!("{what} {bv} → {nv}"));
                    if nv > bv {
                        worse = true;
                    } else {
                        better = true;
                    }
                }
            }
        }
    }
    out.status = if worse {
        "regression"
    } else if better {
        "improvement"
    } else if changed || !out.memory.is_empty() {
        "changed"
    } else {
        "no change"
    }
    .to_string();
    Ok(out)
}

fn image_note(i: &ImageChange) -> String {
    let mut s = format!("image {}", i.verdict);
    if let Some(d) = i.psnr_delta_db {
        s.push_str(&format!(" (PSNR {d:+.2} dB"));
        if let Some(c) = i.changed_pixels {
            s.push_str(&format!(", {c} pixels differ"));
        }
        s.push(')');
    } else if let Some(c) = i.changed_pixels {
        s.push_str(&format!(" ({c} pixels differ)"));
    }
    s
}

fn image_change(
    b: &Row,
    n: &Row,
    base_dir: &Path,
    new_dir: &Path,
    heat_dir: &Path,
    opt: &CompareOptions,
) -> anyhow::Result<ImageChange> {
    let delta = b.psnr_db.zip(n.psnr_db).map(|(b, n)| n - b);
    let mut c = ImageChange {
        psnr_base_db: b.psnr_db,
        psnr_new_db: n.psnr_db,
        psnr_delta_db: delta,
        pixels_changed: None,
        changed_pixels: None,
        max_abs_difference: None,
        heatmap: String::new(),
        verdict: "same".into(),
    };
    if !opt.normalised {
        if !b.image_hash.is_empty() && !n.image_hash.is_empty() {
            c.pixels_changed = Some(b.image_hash != n.image_hash);
        }
        if let (Some(bp), Some(np)) = (
            samples::row_image(base_dir, b),
            samples::row_image(new_dir, n),
        ) {
            let (bi, ni) = (samples::read_f32_image(&bp)?, samples::read_f32_image(&np)?);
            let d = image_difference(&bi, &ni)?;
            c.changed_pixels = Some(d.changed_pixels);
            c.max_abs_difference = Some(d.max_abs);
            c.pixels_changed = Some(d.changed_pixels > 0);
            if d.changed_pixels > 0 {
                std::fs::create_dir_all(heat_dir)
                    .with_context(|| format!("cannot create {}", heat_dir.display()))?;
                let name = format!(
                    "{}__{}__{}__{}.png",
                    crate::results::names::slug(&b.dataset),
                    crate::results::names::viewpoint_slug(&b.viewpoint),
                    crate::results::names::slug(&b.algorithm),
                    crate::results::names::slug(&b.settings.to_string())
                );
                let path = heat_dir.join(&name);
                d.heatmap
                    .save(&path)
                    .with_context(|| format!("cannot write {}", path.display()))?;
                c.heatmap = format!("heatmaps/{name}");
            }
        }
    }
    c.verdict = match delta {
        Some(d) if d < -PSNR_TOLERANCE_DB => "worse",
        Some(d) if d > PSNR_TOLERANCE_DB => "better",
        _ if c.pixels_changed == Some(true) => "changed",
        _ => "same",
    }
    .to_string();
    Ok(c)
}

/// The pooled `total_ms` test per group of [`GroupKey`] (variant × data set × viewport, the
/// reports' groups); the samples are compare's own, per round.
fn group_tests(
    base: &[Row],
    new: &[Row],
    opt: &CompareOptions,
    scale: &[f64],
    rounds: Rounds,
) -> anyhow::Result<Vec<GroupComparison>> {
    let mut out = vec![];
    // Per group, per pair: the median over its rows of ln(NEW/BASE), NEW already divided by
    // its pair's drift (only when `scale` holds one factor per pair).
    let mut paired_logs: Vec<Option<Vec<f64>>> = vec![];
    let pairs = scale.len();
    for (group, matched) in group_round_values(base, new, rounds, opt)? {
        let (mut bs, mut ns, mut views) = (vec![], vec![], 0);
        let mut per_pair: Vec<Vec<f64>> = vec![vec![]; pairs];
        for (bv, nv) in matched {
            let nv = scaled(nv, scale);
            let m = median(&bv);
            if bv.is_empty() || nv.is_empty() || m.is_nan() || m <= 0.0 {
                continue;
            }
            views += 1;
            if pairs > 1 && bv.len() == pairs && nv.len() == pairs {
                for (i, (b, n)) in bv.iter().zip(&nv).enumerate() {
                    if *b > 0.0 && *n > 0.0 {
                        per_pair[i].push((n / b).ln());
                    }
                }
            }
            bs.extend(bv.iter().map(|x| x / m));
            ns.extend(nv.iter().map(|x| x / m));
        }
        if views == 0 {
            continue;
        }
        paired_logs.push(
            (pairs > 1 && per_pair.iter().all(|v| !v.is_empty()))
                .then(|| per_pair.iter().map(|v| median(v)).collect()),
        );
        out.push(GroupComparison {
            total: round_test("total_ms", &bs, &ns, opt, rounds),
            algorithm: group.algorithm,
            settings: group.settings.to_string(),
            dataset: group.dataset,
            width: group.width,
            height: group.height,
            projection: group.projection,
            viewpoints: views,
        });
    }
    // Paired rounds: every group judged by the paired t-test instead (when each has a value
    // per pair and there are enough groups to pool the variance).
    let logs: Option<Vec<Vec<f64>>> = paired_logs.into_iter().collect();
    if let Some(tests) = logs.as_deref().and_then(paired_t_tests) {
        for (g, (ratio, p)) in out.iter_mut().zip(tests) {
            g.total = g
                .total
                .clone()
                .with_paired(ratio, p, opt.threshold, opt.alpha);
        }
    }
    Ok(out)
}

/// One matched row's `total_ms` round values: BASE's, then NEW's as measured (not yet scaled).
type RoundPair = (Vec<f64>, Vec<f64>);

/// Per group of [`GroupKey`] (in BASE's order), the round values of each BASE row and its NEW
/// row (rows only in BASE are left out).
fn group_round_values(
    base: &[Row],
    new: &[Row],
    rounds: Rounds,
    opt: &CompareOptions,
) -> anyhow::Result<Vec<(GroupKey, Vec<RoundPair>)>> {
    GroupKey::distinct(base)
        .into_iter()
        .map(|group| {
            let mut matched = vec![];
            for b in base.iter().filter(|r| group.matches(r)) {
                let Some(n) = new.iter().find(|n| key(n) == key(b)) else {
                    continue;
                };
                matched.push((
                    round_values(b, "total_ms", rounds.base, opt.normalised)?,
                    round_values(n, "total_ms", rounds.new, opt.normalised)?,
                ));
            }
            Ok((group, matched))
        })
        .collect()
}

/// Per group, its NEW/BASE in each pair of rounds: the median over its rows of the row's NEW
/// round value over its BASE round value. Rows whose values do not line up with the rounds (a
/// round failed) are left out; a group left with none is skipped.
fn group_pair_ratios(
    base: &[Row],
    new: &[Row],
    rounds: Rounds,
    opt: &CompareOptions,
) -> anyhow::Result<Vec<Vec<f64>>> {
    let pairs = rounds.base as usize;
    let mut out = vec![];
    for (_, matched) in group_round_values(base, new, rounds, opt)? {
        let mut per_pair: Vec<Vec<f64>> = vec![vec![]; pairs];
        for (bv, nv) in matched {
            if bv.len() != pairs || nv.len() != pairs {
                continue;
            }
            for (i, (b, n)) in bv.iter().zip(&nv).enumerate() {
                if *b > 0.0 && n.is_finite() {
                    per_pair[i].push(n / b);
                }
            }
        }
        if per_pair.iter().all(|v| !v.is_empty()) {
            out.push(per_pair.iter().map(|v| median(v)).collect());
        }
    }
    Ok(out)
}

/// Where two renderings of the same row differ.
pub struct ImageDifference {
    /// Pixels with any channel not bit-identical.
    pub changed_pixels: u64,
    pub max_abs: f64,
    /// Black where identical; changed pixels on a log ramp from 1e-7 (a last-bit change still
    /// shows) to 0.25 and above.
    pub heatmap: image::RgbImage,
}

pub fn image_difference(
    base: &render_core::Image,
    new: &render_core::Image,
) -> anyhow::Result<ImageDifference> {
    if (base.width, base.height) != (new.width, new.height) {
        anyhow::bail!(
            "images differ in size: {}x{} vs {}x{}",
            base.width,
            base.height,
            new.width,
            new.height
        );
    }
    let mut heat = image::RgbImage::new(base.width, base.height);
    let (mut changed, mut max_abs) = (0u64, 0.0f64);
    let (lo, hi) = (1e-7f64.ln(), 0.25f64.ln());
    for (i, (a, b)) in base.pixels.iter().zip(&new.pixels).enumerate() {
        if a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()) {
            continue;
        }
        changed += 1;
        let d = a
            .iter()
            .zip(b)
            .map(|(x, y)| {
                let d = (*x as f64 - *y as f64).abs();
                if d.is_nan() {
                    1.0
                } else {
                    d
                }
            })
            .fold(0.0, f64::max);
        max_abs = max_abs.max(d);
        let t = ((d.max(1e-7).ln() - lo) / (hi - lo)).clamp(0.0, 1.0);
        heat.put_pixel(
            i as u32 % base.width,
            i as u32 / base.width,
            image::Rgb(crate::results::metrics::ramp(t)),
        );
    }
    Ok(ImageDifference {
        changed_pixels: changed,
        max_abs,
        heatmap: heat,
    })
}

#[cfg(test)]
#[path = "compare_tests.rs"]
mod tests;
