//! What one paper's reproduction works with: the [`Session`] (where it writes, the mode, the
//! runs it made), a plan's [`RunSpec`], what was [`Measured`] and the CPU analyses' [`Extra`],
//! the [`Report`] a paper's table writer returns, and the lookups the writers share.

use std::any::Any;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context as _;

use crate::report::{aggregate, Aggregate};
use crate::results::machine::MachineInfo;
use crate::results::{ResultsFile, Row};
use crate::run::matrix::{MatrixArgs, DEFAULT_TF};

use super::claims::ClaimResult;
use super::table::Comparison;

/// What a paper module's table writer returns.
#[derive(Debug, Clone, Default)]
pub struct Report {
    pub comparisons: Vec<Comparison>,
    /// The paper's claims (`reports/papers/claims.csv`), one verdict per data set.
    pub claims: Vec<ClaimResult>,
    pub notes: Vec<String>,
    /// The paper's figures drawn from what was measured.
    pub figures: Vec<Figure>,
}

/// A figure of the paper drawn from what was measured: a heading, what the paper's figure
/// shows and how ours differs (Markdown), and its panels.
#[derive(Debug, Clone, Default)]
pub struct Figure {
    /// The stem of its charts' file names.
    pub key: String,
    pub title: String,
    pub text: String,
    pub panels: Vec<Panel>,
}

/// One panel of a [`Figure`]: counts per screen tile drawn as a heat map, or why there are
/// none.
#[derive(Debug, Clone)]
pub struct Panel {
    /// What it shows in a word or two (a data set): part of its file name.
    pub label: String,
    /// The heat map's title, and the sentence under it.
    pub title: String,
    pub caption: String,
    pub grid: Result<render_core::TileCounts, String>,
}

/// Whether this build has an algorithm (from the algorithm table).
pub fn built_in(algorithm: &str) -> bool {
    crate::algorithms::names().contains(&algorithm)
}

/// Why an algorithm has no rows: not built in (which issue adds it), or `None` if built.
pub fn not_built_reason(algorithm: &str) -> Option<String> {
    (!built_in(algorithm)).then(|| {
        format!(
            "algorithm {algorithm} is not built in (this build has: {})",
            crate::algorithms::names().join(", ")
        )
    })
}

/// One `tetbench run` of a plan.
#[derive(Debug, Clone)]
pub struct RunSpec {
    /// Sub-folder of OUT/<paper>/runs/.
    pub name: String,
    pub algorithms: Vec<String>,
    pub datasets: Vec<String>,
    /// Viewpoints in the full run (the quick run uses [`QUICK_VIEWPOINTS`]).
    pub viewpoints: String,
    pub resolution: u32,
    /// The transfer function (a preset name); `None` is the suite's `low-opacity`.
    pub tf: Option<&'static str>,
    pub settings: Option<String>,
    /// The quick run's settings where they differ from `settings`: only the variants the
    /// paper's tables and claims compare; the others beside them run in the full mode.
    pub quick_settings: Option<String>,
    /// The paper's viewport in every mode: a claim on what the run measures depends on the
    /// viewport (fragment PT's device bytes at 512²), so the quick mode does not halve it.
    pub full_viewport: bool,
    /// The paper's viewpoints in every mode (hardware-independent counts over the views,
    /// such as the ray caster's passes).
    pub full_views: bool,
}

/// The viewport of every paper's plan: 512², stated by the papers or, where one is silent, ours.
pub const PAPER_VIEWPORT: u32 = 512;

impl RunSpec {
    /// A run of one algorithm with the same settings in both modes, at [`PAPER_VIEWPORT`] with
    /// the suite's transfer function, the quick mode shrinking its viewport and views.
    pub fn new(
        name: impl Into<String>,
        algorithm: &str,
        datasets: &[&str],
        viewpoints: &str,
        settings: Option<&str>,
    ) -> RunSpec {
        RunSpec {
            name: name.into(),
            algorithms: vec![algorithm.into()],
            datasets: datasets.iter().map(|d| d.to_string()).collect(),
            viewpoints: viewpoints.into(),
            resolution: PAPER_VIEWPORT,
            tf: None,
            settings: settings.map(String::from),
            quick_settings: None,
            full_viewport: false,
            full_views: false,
        }
    }

    /// The settings of the run in this mode.
    pub fn settings_for(&self, quick: bool) -> Option<&String> {
        match (&self.quick_settings, quick) {
            (Some(q), true) => Some(q),
            _ => self.settings.as_ref(),
        }
    }
}

/// The quick mode's viewpoint (one diagonal of the 14), frames and warm-up.
pub const QUICK_VIEWPOINTS: &str = "+x+y+z";
pub const QUICK_FRAMES: u32 = 1;
/// The quick mode divides the paper's viewport side by this (fragments, and so the time of
/// every rasterising algorithm on a CPU adapter, scale with the pixels).
pub const QUICK_RESOLUTION_DIVISOR: u32 = 2;
pub const QUICK_WARMUP: u32 = 1;
/// The full mode's frames and warm-up (tetbench's standard).
pub const FULL_FRAMES: u32 = crate::run::suite::STANDARD_FRAMES;
pub const FULL_WARMUP: u32 = crate::run::suite::STANDARD_WARMUP;
/// The full mode's rounds per row: each row's frames are taken at five moments, seconds
/// apart, so that a GPU timing claim reads holds, does not hold or a real within noise.
pub const FULL_ROUNDS: u32 = 5;

/// Measured rows of one paper plus what could not be measured.
#[derive(Debug, Clone, Default)]
pub struct Measured {
    pub rows: Vec<Row>,
    /// Per run, the failures that are not one row (a data set that did not load).
    pub errors: Vec<String>,
    /// The adapter's calibration from the first run's machine record that has one (claims
    /// normalised by a peak read it).
    pub calibration: Option<crate::results::machine::Calibration>,
    /// The run folder of each row, by index in `rows` (its image paths are relative to it;
    /// rows pushed without one have none).
    pub row_dirs: Vec<Option<PathBuf>>,
}

impl Measured {
    /// Adds a run's rows, read from `dir`.
    pub fn push_run(&mut self, dir: &std::path::Path, rows: impl IntoIterator<Item = Row>) {
        self.row_dirs.resize(self.rows.len(), None);
        for row in rows {
            self.rows.push(row);
            self.row_dirs.push(Some(dir.to_path_buf()));
        }
    }

    pub fn aggregates(&self) -> Vec<Aggregate> {
        aggregate(&self.rows)
    }

    /// A counter of the first row of `algorithm` on `dataset` that has it.
    pub fn counter(&self, algorithm: &str, dataset: &str, name: &str) -> Option<f64> {
        self.rows
            .iter()
            .filter(|r| r.algorithm == algorithm && r.dataset == dataset)
            .find_map(|r| r.counter(name))
    }

    /// Why `algorithm` has no value on `dataset`: not built, a failed row's error, a data set
    /// that did not load, or not measured.
    pub fn why(&self, algorithm: &str, dataset: &str) -> String {
        if let Some(r) = not_built_reason(algorithm) {
            return r;
        }
        if let Some(r) = self
            .rows
            .iter()
            .find(|r| r.algorithm == algorithm && r.dataset == dataset && !r.ok())
        {
            return format!("failed: {}", r.error_text());
        }
        if let Some(e) = self
            .errors
            .iter()
            .find(|e| e.contains(&format!("\"{dataset}\"")))
        {
            return e.clone();
        }
        "not measured in this run".into()
    }
}

/// The aggregate of `algorithm` on `dataset` whose settings include every `want` pair, if
/// exactly one does: where several variants match, none is taken (the first one found must
/// never stand for the algorithm silently; the table's plan names the variant).
pub fn find<'a>(
    aggs: &'a [Aggregate],
    algorithm: &str,
    dataset: &str,
    pins: &[(&str, &str)],
) -> Option<&'a Aggregate> {
    let want = pins
        .iter()
        .fold(render_core::Settings::new(), |s, (k, v)| s.with(k, *v));
    find_including(
        aggs,
        algorithm,
        dataset,
        &want.retyped(|k| crate::algorithms::describe(algorithm).and_then(|d| d.kind_of(k))),
    )
}

/// The one aggregate of `algorithm` on `dataset` whose settings include the variant a paper's
/// table names as text (its own constant: a typo there is a bug, so it panics).
pub fn find_variant<'a>(
    aggs: &'a [Aggregate],
    algorithm: &str,
    dataset: &str,
    settings: &str,
) -> Option<&'a Aggregate> {
    let want = crate::algorithms::parse_settings(algorithm, settings)
        .expect("a table's own settings parse");
    find_including(aggs, algorithm, dataset, &want)
}

/// The one aggregate of `algorithm` on `dataset` whose settings include `want` (`None` when
/// none or several do); a positive control's perturbed variant only where `want` names its key.
pub fn find_including<'a>(
    aggs: &'a [Aggregate],
    algorithm: &str,
    dataset: &str,
    want: &render_core::Settings,
) -> Option<&'a Aggregate> {
    let mut hits = aggs.iter().filter(|a| {
        a.algorithm == algorithm
            && a.dataset == dataset
            && a.settings.includes(want)
            && !crate::algorithms::perturbed_beyond(algorithm, &a.settings, want)
    });
    let first = hits.next()?;
    hits.next().is_none().then_some(first)
}

/// The state of one paper's reproduction: where it writes, the mode, and what it ran.
pub struct Session {
    pub dir: PathBuf,
    pub quick: bool,
    pub data_dir: Option<PathBuf>,
    pub cache_dir: Option<PathBuf>,
    pub substitutes: Vec<(String, String)>,
    pub resolution: Option<u32>,
    /// `--rounds`: rounds per row (`None`: [`FULL_ROUNDS`] in the full mode, 1 in quick).
    pub rounds: Option<u32>,
    /// The machine of the first run (adapter included), for the conditions.
    pub machine: Option<MachineInfo>,
    /// The equivalent `tetbench run` command of every run, and its outcome.
    pub log: Vec<String>,
    /// External renderers added to every run (`--external`).
    pub external: crate::run::matrix::ExternalArgs,
    /// The commit the binary was built from and whether the tree was clean.
    pub source: SourceState,
    /// Set by `tetbench analyze PAPER RUN_DIR`: the runs the tables come from.
    pub from_run: Option<PathBuf>,
}

impl Session {
    /// The data set the plan calls `name` (or its substitute).
    pub fn dataset(&self, name: &str) -> String {
        self.substitutes
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, s)| s.clone())
            .unwrap_or_else(|| name.to_string())
    }

    /// Loads the data set the plan calls `name` for a CPU analysis; a failure goes to
    /// `measured.errors`, naming the data set.
    pub fn load(&self, name: &str, measured: &mut Measured) -> Option<datasets::Dataset> {
        let registry = datasets::registry::Registry::new(self.data_dir.clone());
        match registry.resolve(&self.dataset(name), &datasets::LoadOptions::default()) {
            Ok(ds) => Some(ds),
            Err(e) => {
                measured
                    .errors
                    .push(format!("data set \"{name}\" could not be loaded: {e}"));
                None
            }
        }
    }

    /// Rounds per row in this mode.
    pub fn rounds(&self) -> u32 {
        self.rounds
            .unwrap_or(if self.quick { 1 } else { FULL_ROUNDS })
    }

    /// The viewport of a plan entry: as [`Session::resolution`], never halved where the entry
    /// needs the paper's viewport.
    pub fn resolution_of(&self, spec: &RunSpec) -> u32 {
        if spec.full_viewport {
            self.resolution.unwrap_or(spec.resolution)
        } else {
            self.resolution(spec.resolution)
        }
    }

    /// The viewport of a run: `--resolution`, else the paper's (halved in quick mode).
    pub fn resolution(&self, paper: u32) -> u32 {
        self.resolution.unwrap_or(if self.quick {
            paper / QUICK_RESOLUTION_DIVISOR
        } else {
            paper
        })
    }

    /// Runs one plan entry with the built-in algorithms it names; rows keep the plan's data
    /// set names (substitutes are renamed back so the tables find them).
    pub fn run(&mut self, spec: &RunSpec, measured: &mut Measured) -> anyhow::Result<()> {
        let algorithms: Vec<String> = spec
            .algorithms
            .iter()
            .filter(|a| built_in(a))
            .cloned()
            .collect();
        for a in spec.algorithms.iter().filter(|a| !built_in(a)) {
            self.log.push(format!(
                "run {}: {a} skipped ({})",
                spec.name,
                not_built_reason(a).unwrap_or_default()
            ));
        }
        if algorithms.is_empty() {
            return Ok(());
        }
        let viewpoints = if self.quick && !spec.full_views {
            QUICK_VIEWPOINTS.to_string()
        } else {
            spec.viewpoints.clone()
        };
        let datasets: Vec<String> = spec.datasets.iter().map(|d| self.dataset(d)).collect();
        let out = self.dir.join("runs").join(&spec.name);
        let matrix = MatrixArgs {
            algorithms: algorithms.clone(),
            datasets: datasets.clone(),
            viewpoints: Some(viewpoints.clone()),
            resolution: Some(self.resolution_of(spec)),
            tf: Some(spec.tf.unwrap_or(DEFAULT_TF).into()),
            frames: Some(if self.quick {
                QUICK_FRAMES
            } else {
                FULL_FRAMES
            }),
            warmup: Some(if self.quick {
                QUICK_WARMUP
            } else {
                FULL_WARMUP
            }),
            settings: spec.settings_for(self.quick).cloned(),
            rounds: Some(self.rounds()),
            no_reference: self.quick,
            cache_dir: self.cache_dir.clone(),
            external: self.external.clone(),
            ..MatrixArgs::default()
        };
        let args = matrix.plan(out.clone());
        let command = format!(
            "tetbench run --algorithms {} --datasets {} --viewpoints {viewpoints} --resolution {}{}{}{}",
            algorithms.join(","),
            datasets.join(","),
            self.resolution_of(spec),
            spec.tf.map(|t| format!(" --tf {t}")).unwrap_or_default(),
            spec.settings_for(self.quick)
                .map(|s| format!(" --settings '{s}'"))
                .unwrap_or_default(),
            if self.quick {
                format!(" --frames {QUICK_FRAMES} --warmup {QUICK_WARMUP} --no-reference")
            } else {
                String::new()
            }
        ) + &if self.rounds() > 1 {
            format!(" --rounds {}", self.rounds())
        } else {
            String::new()
        };
        let config = args.to_config(self.data_dir.clone(), vec![command.clone()])?;
        let filter = config.settings_filter.clone();
        let t0 = Instant::now();
        let outcome = crate::run::run(&config, &|name: &str| matrix.variants(name, &filter))
            .with_context(|| format!("run {}", spec.name))?;
        let file = ResultsFile::read(&out)?;
        if self.machine.is_none() {
            self.machine = Some(file.machine.clone());
        }
        if measured.calibration.is_none() {
            measured.calibration = file.machine.calibration.clone();
        }
        self.log.push(format!(
            "run {}: `{command}` — {} rows, {} failed, {:.0} s",
            spec.name,
            outcome.rows,
            outcome.failed_rows,
            t0.elapsed().as_secs_f64()
        ));
        measured.errors.extend(outcome.errors.iter().cloned());
        let rows = file.rows.into_iter().map(|mut row| {
            if let Some((plan, _)) = self.substitutes.iter().find(|(_, s)| {
                crate::results::names::slug(s) == crate::results::names::slug(&row.dataset)
                    || *s == row.dataset
            }) {
                row.dataset = plan.clone();
            }
            row
        });
        measured.push_run(&out, rows);
        Ok(())
    }
}

/// Whether a data set name is a generated stand-in (its rows are marked).
pub fn is_standin(name: &str) -> bool {
    datasets::standins::is_generated(name)
}

/// What a paper measured besides run rows: the data set sizes every paper may need, and the
/// paper's own CPU analyses as its module's type (sorts and the k-buffer for HAVS, the
/// classifier for GATOR), which only that module reads back ([`Extra::own`]). The shape is
/// shared so the tests can call every table writer alike; it names no paper's types.
#[derive(Clone, Default)]
pub struct Extra {
    /// Data set sizes: (plan name, points, tets).
    pub sizes: Vec<(String, u64, u64)>,
    /// Zero-volume tets the loader dropped, per data set (plan name, count).
    pub dropped: Vec<(String, u64)>,
    /// The paper's own analyses (`None`: not run).
    pub own: Option<Arc<dyn Any + Send + Sync>>,
}

impl std::fmt::Debug for Extra {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Extra")
            .field("sizes", &self.sizes)
            .field("dropped", &self.dropped)
            .field("own", &self.own.as_ref().map(|_| "…"))
            .finish()
    }
}

impl Extra {
    /// An `Extra` holding a paper's own analyses.
    pub fn with_own<T: Any + Send + Sync>(own: T) -> Extra {
        Extra {
            own: Some(Arc::new(own)),
            ..Extra::default()
        }
    }

    /// The paper's own analyses, if they are of type `T`.
    pub fn own<T: Any>(&self) -> Option<&T> {
        self.own.as_deref()?.downcast_ref::<T>()
    }

    /// The points and tets of data set `d`, where it was loaded.
    pub fn size(&self, d: &str) -> Option<(u64, u64)> {
        self.sizes
            .iter()
            .find(|(n, _, _)| n == d)
            .map(|&(_, points, tets)| (points, tets))
    }

    /// Tets of zero volume the loader dropped from data set `d` (0 when none or not loaded).
    pub fn dropped_by_loader(&self, d: &str) -> u64 {
        self.dropped
            .iter()
            .find(|(n, _)| n == d)
            .map_or(0, |(_, n)| *n)
    }
}

/// The commit `reproduce` runs from and whether the tree has uncommitted changes (read the
/// way the run's machine record reads it, [`MachineInfo::collect`]).
#[derive(Debug, Clone, Default)]
pub struct SourceState {
    pub commit: Option<String>,
    pub dirty: Option<bool>,
    /// `--allow-dirty` was given.
    pub allowed_dirty: bool,
}

impl SourceState {
    pub fn read() -> SourceState {
        let m = MachineInfo::collect();
        SourceState {
            commit: m.git_commit,
            dirty: m.git_dirty,
            allowed_dirty: false,
        }
    }

    /// Refuses a tree with uncommitted changes unless allowed.
    pub fn check(&mut self, allow_dirty: bool) -> anyhow::Result<()> {
        if self.dirty == Some(true) && !allow_dirty {
            anyhow::bail!(
                "the working tree has uncommitted changes: commit them so the reports name one commit, or pass --allow-dirty (the reports will say so)"
            );
        }
        self.allowed_dirty = allow_dirty && self.dirty == Some(true);
        Ok(())
    }

    /// One sentence for the reports.
    pub fn describe(&self) -> String {
        let commit = self.commit.as_deref().unwrap_or("unknown (no git)");
        match self.dirty {
            Some(true) => format!(
                "Built from commit `{commit}` **with uncommitted changes** (`--allow-dirty`): these figures are not reproducible from the commit alone."
            ),
            Some(false) => format!("Built from commit `{commit}`, clean tree."),
            None => format!("Commit `{commit}`; whether the tree was clean is unknown."),
        }
    }
}
