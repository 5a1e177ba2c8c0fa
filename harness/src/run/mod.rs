//! The run loop: every data set × algorithm variant × viewpoint, measured and compared with the
//! exact reference, each row written the moment it is done.
//!
//! Per data set the mesh is loaded once and each renderer prepares it once; per viewpoint the
//! renderer draws `warmup` untimed frames, then `frames` timed ones, then its image is read back
//! (outside the timing) and compared with the reference. A failure in one row (out of GPU
//! memory, a device error, even a panic in a renderer) is recorded in that row and the run goes
//! on; finished rows are never lost.

use std::collections::HashMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{anyhow, Context};
use datasets::LazyDataset;
use render_core::{
    Camera, FrameStats, Gpu, Image, Optics, Projection, Renderer, TransferFunction, Viewpoint,
};

pub use crate::results::names::{dataset_label, slug, viewpoint_slug};

use crate::algorithms::SettingsFilter;
use crate::report::progress::Progress;
use crate::results::machine::MachineInfo;
use crate::results::metrics::{self, summarize};
use crate::results::{ResultsWriter, Row, RunDescription, Viewpoints};

pub mod allocator;
pub mod control;
pub mod lock;
pub mod matrix;
mod measure;
mod perf_control;
pub mod plan;
pub mod resume;
pub mod shard;
pub mod suite;
use measure::DatasetContext;

/// Everything a run needs, already parsed and checked.
#[derive(Debug, Clone)]
pub struct RunConfig {
    pub algorithms: Vec<String>,
    pub datasets: Vec<String>,
    pub viewpoints: Viewpoints,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub warmup: u32,
    /// Passes over a data set's variants: each pass renders `warmup` + `frames` per viewpoint
    /// of every variant in turn, so a row's samples come from `rounds` separate moments
    /// (see [`DatasetContext::run_variants`]). 1: each variant runs alone, then is dropped.
    pub rounds: u32,
    pub tf_spec: String,
    pub tf: TransferFunction,
    pub projection: Projection,
    pub out: PathBuf,
    pub data_dir: Option<PathBuf>,
    /// Where reference images are cached between runs.
    pub cache_dir: PathBuf,
    /// Compare with the reference (and write heatmaps); off with `--no-reference`.
    pub reference: bool,
    pub settings_filter: SettingsFilter,
    pub scalar: Option<String>,
    pub command_line: Vec<String>,
    /// Write the HTML report and charts at the end.
    pub report: bool,
    /// Make suspect rows ([`crate::results::suspect`]) an error (non-zero exit), for CI.
    pub strict: bool,
    /// Run only this part of the matrix (`--shard i/N`, see [`crate::run::shard`]).
    pub shard: Option<crate::run::shard::Shard>,
    /// Calibrate the backend (or reuse the cached figures) and add the roofline columns.
    pub calibrate: bool,
    /// Keep the finished units of an earlier run of the same plan in `out` and measure only
    /// the rest (`run --resume`, [`resume`]).
    pub resume: bool,
    /// External renderers (`--external`): each spec is one variant of the algorithm it names.
    pub externals: Vec<external_peer::ExternalSpec>,
}

/// Makes the variants of an algorithm by name (normally
/// [`crate::algorithms::selected_variants`] with the run's filter; tests pass their own).
pub type VariantFactory<'a> = &'a dyn Fn(&str) -> anyhow::Result<Vec<Box<dyn Renderer>>>;

/// What a finished run produced.
#[derive(Debug, Clone, Default)]
pub struct RunOutcome {
    pub rows: usize,
    pub failed_rows: usize,
    /// Rows whose image error is out of line with the others on the same image
    /// ([`crate::results::suspect`]): measured, but probably a renderer defect.
    pub suspect_rows: Vec<String>,
    /// Rows whose fastest frame beat their roofline bound ([`crate::calibrate::beats_bound`]):
    /// a defect of the bound, listed so that it is seen.
    pub beaten_bounds: Vec<String>,
    /// Set when rows beat the cached calibration's bound and the backend was calibrated again
    /// after the run (what happened, in one sentence).
    pub recalibrated: Option<String>,
    /// Failures that are not one row (a data set that did not load, a missing reference).
    pub errors: Vec<String>,
    pub seconds: f64,
}

impl RunOutcome {
    pub fn all_ok(&self) -> bool {
        self.failed_rows == 0 && self.errors.is_empty()
    }
}

fn panic_message(p: Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".into()
    }
}

/// Runs `f`, turning a panic into an error so one faulty row cannot end the run.
fn guarded<T>(what: &str, f: impl FnOnce() -> anyhow::Result<T>) -> anyhow::Result<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(p) => Err(anyhow!("{what} panicked: {}", panic_message(p))),
    }
}

fn projection_name(p: &Projection) -> String {
    match p {
        Projection::Perspective { fovy_deg } => format!("perspective{fovy_deg}"),
        Projection::Orthographic => "orthographic".into(),
    }
}

/// The variants of every asked-for algorithm that pass the settings filter, checked before any
/// work starts: unknown algorithms, unknown filter keys and filters that leave nothing are
/// errors here, not after an hour of measuring.
fn plan_variants(
    config: &RunConfig,
    factory: VariantFactory,
) -> anyhow::Result<Vec<(String, usize)>> {
    let mut all_settings = vec![];
    let mut kept = vec![];
    for name in &config.algorithms {
        let variants = factory(name)?;
        let n = variants
            .iter()
            .filter(|r| config.settings_filter.accepts(&r.settings()))
            .count();
        all_settings.extend(variants.iter().map(|r| r.settings()));
        // The filter may have selected nothing of this algorithm; its keys still exist.
        if let Ok(defaults) = crate::algorithms::variants(name) {
            all_settings.extend(defaults.iter().map(|r| r.settings()));
        }
        kept.push((name.clone(), n));
    }
    let unknown = config.settings_filter.unknown_keys(all_settings.iter());
    if !unknown.is_empty() {
        let mut keys: Vec<&str> = all_settings.iter().flat_map(|s| s.keys()).collect();
        keys.sort();
        keys.dedup();
        anyhow::bail!(
            "--settings: no algorithm has the setting(s) {}; known: {}",
            unknown.join(", "),
            keys.join(", ")
        );
    }
    // A value no variant of an asked-for algorithm has is a typo that would silently drop the
    // algorithm from the run: refuse it, naming what the algorithm offers. An
    // algorithm without the key at all keeps its defaults.
    for (name, n) in &kept {
        let Ok(all) = crate::algorithms::all_variants(name) else {
            continue; // not in the table (tests pass their own factories)
        };
        let offered: Vec<render_core::Settings> = all.iter().map(|r| r.settings()).collect();
        for (key, values) in &config.settings_filter.terms {
            let mut has: Vec<String> = vec![];
            for value in offered.iter().filter_map(|s| s.text(key)) {
                if !has.contains(&value) {
                    has.push(value);
                }
            }
            if has.is_empty() {
                continue;
            }
            let unknown: Vec<&str> = values
                .iter()
                .map(String::as_str)
                .filter(|v| !has.iter().any(|h| h == v))
                .collect();
            if !unknown.is_empty() {
                anyhow::bail!(
                    "--settings {key}={}: {name} has no variant with {key}={}; it offers {key}={}",
                    values.join("|"),
                    unknown.join("|"),
                    has.join("|")
                );
            }
        }
        if *n == 0 {
            let variants: Vec<String> = all.iter().map(|r| r.settings().to_string()).collect();
            anyhow::bail!(
                "--settings {} leaves no variant of {name} to run: each value exists, but no \
                 variant combines them; its variants are:\n  {}",
                config.settings_filter,
                variants.join("\n  ")
            );
        }
    }
    if kept.iter().all(|(_, n)| *n == 0) {
        anyhow::bail!(
            "--settings {} leaves no variant of {} to run",
            config.settings_filter,
            config.algorithms.join(", ")
        );
    }
    Ok(kept)
}

/// Checks every data set name before anything is measured, so that a typo fails at once with
/// what to do instead of after the other data sets' rows.
fn check_datasets(config: &RunConfig) -> anyhow::Result<()> {
    let registry = datasets::registry::Registry::new(config.data_dir.clone());
    let problems: Vec<String> = config
        .datasets
        .iter()
        .filter_map(|spec| registry.check(spec).err().map(|e| format!("  {spec}: {e}")))
        .collect();
    if !problems.is_empty() {
        anyhow::bail!(
            "--datasets: {} of {} cannot be used, nothing was measured:\n{}\n\
             (`tetbench datasets list` shows the named data sets and generators; named ones are \
             read from the data directory: --data-dir DIR or TETBENCH_DATA)",
            problems.len(),
            config.datasets.len(),
            problems.join("\n")
        );
    }
    Ok(())
}

/// Runs the whole plan, writing `results.csv`, `results.json`, images and (if asked) the
/// report into `config.out`.
pub fn run(config: &RunConfig, factory: VariantFactory) -> anyhow::Result<RunOutcome> {
    let started = Instant::now();
    // External renderers are built from the run's own specs, whatever factory the caller gave.
    let with_externals = |name: &str| match external_variants(config, name) {
        Some(v) => Ok(v),
        None => factory(name),
    };
    let factory: VariantFactory = &with_externals;
    let plan = plan_variants(config, factory)?;
    check_datasets(config)?;
    let variants_total: usize = plan.iter().map(|(_, n)| n).sum();
    // Held until the run returns: a second run into this directory refuses (lock.rs).
    let _lock = lock::acquire(&config.out, &config.command_line)?;
    let (gpu, machine) = open_machine(config)?;
    // The control beside the rows (with the roofline: `--no-calibrate` turns both off).
    let probes = config
        .calibrate
        .then(|| crate::calibrate::probes::ProbeContext::new(&gpu));
    let mut control = probes
        .as_ref()
        .map(|p| control::RunControl::new(p, started));
    let description = run_description(config);
    let kept = if config.resume {
        resume::finished_rows(&config.out, &description, &machine, config.viewpoints.len())?
    } else {
        vec![]
    };
    let scope = Scope {
        shard: match config.shard {
            Some(shard) => Some(shard::select(shard, &matrix_units(config, factory)?)),
            None => None,
        },
        done: kept
            .iter()
            .map(|r| (r.dataset.clone(), r.algorithm.clone(), r.settings.clone()))
            .collect(),
        variants_total,
    };
    let mut writer = ResultsWriter::create(&config.out, machine, description)?;
    writer.push_restored(kept)?;
    let mut progress = start_progress(config, &gpu, &scope, &writer);
    let mut outcome = RunOutcome::default();
    let registry = datasets::registry::Registry::new(config.data_dir.clone());
    for spec in &config.datasets {
        let label = dataset_label(spec);
        if scope.units_of(&label) == 0 || scope.finished(&label) {
            continue; // nothing of it in this shard, or all of it kept by --resume
        }
        let Some(dataset) =
            load_dataset(config, &registry, spec, &scope, &mut progress).or_else(|msg| {
                writer.push_error(msg.clone())?;
                outcome.errors.push(msg);
                anyhow::Ok(None)
            })?
        else {
            continue;
        };
        let mut renderers = vec![];
        for (name, _) in &plan {
            renderers.extend(
                factory(name)?
                    .into_iter()
                    .filter(|r| scope.runs(config, &label, name, &r.settings())),
            );
        }
        let optics =
            Optics::for_extent(config.tf.clone(), &dataset.bounds(), dataset.scalar_range());
        let mut ctx = DatasetContext::new(config, &gpu, &dataset, &optics, label);
        measure_dataset(
            &mut ctx,
            renderers,
            &mut control,
            &mut writer,
            &mut progress,
            &mut outcome,
        )?;
    }
    progress.finish();
    finish_run(config, &gpu, &mut writer, &mut outcome)?;
    outcome.seconds = started.elapsed().as_secs_f64();
    Ok(outcome)
}

/// Measures `renderers` on one data set. In one round, one variant at a time (its GPU memory
/// freed before the next one prepares), the control taken before the first, between variants
/// when it is due and after the last; in several, all variants round after round, the control
/// taken with each round ([`DatasetContext::run_variants`]).
fn measure_dataset(
    ctx: &mut DatasetContext<'_>,
    renderers: Vec<Box<dyn Renderer>>,
    control: &mut Option<control::RunControl>,
    writer: &mut ResultsWriter,
    progress: &mut Progress,
    outcome: &mut RunOutcome,
) -> anyhow::Result<()> {
    if ctx.config.rounds > 1 {
        return ctx.run_variants(renderers, writer, progress, outcome, control);
    }
    for (i, renderer) in renderers.into_iter().enumerate() {
        if let Some(c) = control.as_mut().filter(|c| i == 0 || c.due()) {
            c.take(&ctx.label, 0, writer, progress);
        }
        ctx.run_variants(vec![renderer], writer, progress, outcome, &mut None)?;
    }
    if let Some(c) = control.as_mut() {
        c.take(&ctx.label, 1, writer, progress);
    }
    Ok(())
}

/// The units of the matrix this invocation runs: its shard's (all without `--shard`), less
/// those a resumed run already finished.
struct Scope {
    /// The (data set, algorithm, settings) units of this shard; `None`: all.
    shard: Option<std::collections::HashSet<shard::Unit>>,
    /// Units whose rows `--resume` kept.
    done: std::collections::HashSet<resume::Unit>,
    /// Variants per data set over all algorithms (without a shard, every data set's units).
    variants_total: usize,
}

impl Scope {
    /// Units of data set `label` in this shard.
    fn units_of(&self, label: &str) -> usize {
        match &self.shard {
            Some(u) => u.iter().filter(|(d, _, _)| d == label).count(),
            None => self.variants_total,
        }
    }

    fn units_total(&self, datasets: usize) -> usize {
        match &self.shard {
            Some(u) => u.len(),
            None => datasets * self.variants_total,
        }
    }

    /// Whether every unit of data set `label` was kept by `--resume`.
    fn finished(&self, label: &str) -> bool {
        self.done.iter().filter(|(d, _, _)| d == label).count() == self.units_of(label)
    }

    /// Whether this invocation runs the variant `settings` of `algorithm` on `label`.
    fn runs(
        &self,
        config: &RunConfig,
        label: &str,
        algorithm: &str,
        settings: &render_core::Settings,
    ) -> bool {
        let unit = (label.to_string(), algorithm.to_string(), settings.clone());
        config.settings_filter.accepts(settings)
            && self.shard.as_ref().is_none_or(|u| u.contains(&unit))
            && !self.done.contains(&unit)
    }
}

/// Opens the GPU and records the machine, calibrating the backend unless `--no-calibrate`.
fn open_machine(config: &RunConfig) -> anyhow::Result<(Gpu, MachineInfo)> {
    let gpu = Gpu::new()?;
    let mut machine = MachineInfo::collect();
    machine.adapter = Some(gpu.adapter.clone());
    if config.calibrate {
        let t0 = Instant::now();
        let (cal, cached) =
            crate::calibrate::cached_or_measure(&gpu, &machine, &config.cache_dir, false)
                .context("calibrating the backend (skip with --no-calibrate)")?;
        if !cached {
            eprintln!(
                "tetbench: calibrated the backend in {:.1} s (cached for later runs)",
                t0.elapsed().as_secs_f64()
            );
        }
        machine.calibration = Some(cal);
    }
    Ok((gpu, machine))
}

/// How the run was asked for, as `results.json` keeps it.
fn run_description(config: &RunConfig) -> RunDescription {
    RunDescription {
        command_line: config.command_line.clone(),
        algorithms: config.algorithms.clone(),
        datasets: config.datasets.clone(),
        viewpoints: config.viewpoints.clone(),
        width: config.width,
        height: config.height,
        frames: config.frames,
        warmup: config.warmup,
        rounds: config.rounds,
        transfer_function: config.tf_spec.clone(),
        projection: projection_name(&config.projection),
        settings_filter: config.settings_filter.clone(),
        reference: config.reference,
        shard: config.shard,
        merged_from: vec![],
    }
}

/// The progress display over this invocation's rows, with what `--resume` kept already
/// counted, and the run's first lines.
fn start_progress(
    config: &RunConfig,
    gpu: &Gpu,
    scope: &Scope,
    writer: &ResultsWriter,
) -> Progress {
    let views = config.viewpoints.len();
    let mut progress = Progress::new(
        "",
        (scope.units_total(config.datasets.len()) * views) as u64,
        "rows",
    );
    if !scope.done.is_empty() {
        progress.log(&format!(
            "tetbench: --resume keeps {} finished unit(s) ({} rows) of {}",
            scope.done.len(),
            writer.file.rows.len(),
            config.out.display()
        ));
        progress.skip((scope.done.len() * views) as u64);
    }
    progress.log(&format!(
        "tetbench: {} on {} ({}, {}); writing {}",
        config.algorithms.join(","),
        gpu.adapter.name,
        gpu.adapter.backend,
        gpu.adapter.device_type,
        config.out.display()
    ));
    progress
}

/// Loads one data set (lazily: a voxel volume's tets are split only when a variant needs
/// them). A data set that cannot be loaded is the error message (its rows are skipped in the
/// progress display), not a failed run.
fn load_dataset(
    config: &RunConfig,
    registry: &datasets::registry::Registry,
    spec: &str,
    scope: &Scope,
    progress: &mut Progress,
) -> Result<Option<LazyDataset>, String> {
    let label = dataset_label(spec);
    progress.status(&format!("loading {label}"));
    let t0 = Instant::now();
    let load_options = datasets::LoadOptions {
        scalar: config.scalar.clone(),
        ..Default::default()
    };
    let dataset = guarded("loading", || {
        registry
            .resolve_lazy(spec, &load_options)
            .map_err(|e| anyhow!("{e}"))
    })
    .map_err(|e| {
        let msg = format!("data set {spec:?} could not be loaded: {e:#}");
        progress.log(&format!("ERROR: {msg}"));
        progress.skip((scope.units_of(&label) * config.viewpoints.len()) as u64);
        msg
    })?;
    progress.log(&format!(
        "{label}: {} points, {} tets{} (loaded in {:.2} s)",
        dataset.num_points(),
        dataset.num_tets(),
        if dataset.tets_built() {
            ""
        } else {
            ", not split yet"
        },
        t0.elapsed().as_secs_f64()
    ));
    Ok(Some(dataset))
}

/// What needs every row: the suspect flags, the roofline columns (with a calibration), both
/// files rewritten, the end load and time, and the report.
fn finish_run(
    config: &RunConfig,
    gpu: &Gpu,
    writer: &mut ResultsWriter,
    outcome: &mut RunOutcome,
) -> anyhow::Result<()> {
    crate::results::suspect::mark_all(&mut writer.file.rows);
    outcome.suspect_rows = writer
        .file
        .rows
        .iter()
        .filter_map(|r| {
            let why = r.suspect.as_ref()?;
            Some(format!(
                "{} {} on {} {}: {why}",
                r.algorithm, r.settings, r.dataset, r.viewpoint
            ))
        })
        .collect();
    if let Some(cal) = writer.file.machine.calibration.clone() {
        if let Some(control) = writer.file.control.clone() {
            control::attach(&mut writer.file.rows, &control, config.rounds.max(1));
        }
        crate::calibrate::annotate(&mut writer.file.rows, &cal);
        // Rows priced by their own control need no second calibration: a bound they beat is
        // listed as the defect it is.
        let uncontrolled = writer.file.control.is_none();
        if config.calibrate
            && uncontrolled
            && writer.file.rows.iter().any(crate::calibrate::beats_bound)
        {
            recalibrate_after(config, gpu, writer, outcome)?;
        }
    }
    outcome.beaten_bounds = beaten_bounds(&writer.file.rows);
    // Columns only known once every row is in (suspect flags, roofline): both files again.
    writer.rewrite_all()?;
    writer.file.machine.load_average_end = crate::results::machine::load_average();
    writer.finish()?;
    outcome.rows = writer.file.rows.len();
    if config.report {
        crate::report::write(&config.out, &writer.file).context("writing the report")?;
    }
    Ok(())
}

/// A row faster than its bound shows that a cached figure was not the backend's peak at this
/// run's moment (a VM's speed drifts by ×2 within an hour, docs/roofline.md): the backend is
/// measured again now, each figure the best of the new measurement and the cache
/// ([`crate::calibrate::cached_or_measure`] with `force`), and the rows are priced again.
fn recalibrate_after(
    config: &RunConfig,
    gpu: &Gpu,
    writer: &mut ResultsWriter,
    outcome: &mut RunOutcome,
) -> anyhow::Result<()> {
    let beaten = |rows: &[Row]| {
        rows.iter()
            .filter(|r| crate::calibrate::beats_bound(r))
            .count()
    };
    let before = beaten(&writer.file.rows);
    let t0 = Instant::now();
    let (cal, _) =
        crate::calibrate::cached_or_measure(gpu, &writer.file.machine, &config.cache_dir, true)
            .context("calibrating the backend again after the run")?;
    crate::calibrate::annotate(&mut writer.file.rows, &cal);
    writer.file.machine.calibration = Some(cal);
    outcome.recalibrated = Some(format!(
        "{before} row(s) beat the bound of the cached calibration: calibrated again after the run in {:.1} s (each figure the best of both), {} beat it now",
        t0.elapsed().as_secs_f64(),
        beaten(&writer.file.rows)
    ));
    Ok(())
}

/// One line per row whose fastest frame beat its roofline ([`crate::calibrate::beats_bound`]).
pub fn beaten_bounds(rows: &[Row]) -> Vec<String> {
    rows.iter()
        .filter(|r| crate::calibrate::beats_bound(r))
        .map(|r| {
            format!(
                "{} {} on {} {}: {} bound {:.3} ms, fastest frame {:.3} ms (limit fraction {:.2})",
                r.algorithm,
                r.settings,
                r.dataset,
                r.viewpoint,
                r.bound_by.map_or("", crate::results::Bound::name),
                r.roofline_ms.unwrap_or(f64::NAN),
                r.total_ms_min.unwrap_or(f64::NAN),
                r.limit_fraction.unwrap_or(f64::NAN)
            )
        })
        .collect()
}

/// The variants of an external renderer named `name` (one per `--external` spec with that
/// name), or `None` when `name` is not one.
fn external_variants(config: &RunConfig, name: &str) -> Option<Vec<Box<dyn Renderer>>> {
    let v: Vec<Box<dyn Renderer>> = config
        .externals
        .iter()
        .filter(|s| s.name == name)
        .map(|s| Box::new(external_peer::ExternalRenderer::new(s.clone())) as Box<dyn Renderer>)
        .collect();
    (!v.is_empty()).then_some(v)
}

/// Every (data set, algorithm, settings) of the run, for `--shard`.
fn matrix_units(
    config: &RunConfig,
    factory: VariantFactory,
) -> anyhow::Result<Vec<crate::run::shard::Unit>> {
    let mut units = vec![];
    for spec in &config.datasets {
        for name in &config.algorithms {
            for r in factory(name)?
                .iter()
                .filter(|r| config.settings_filter.accepts(&r.settings()))
            {
                units.push((dataset_label(spec), name.clone(), r.settings()));
            }
        }
    }
    Ok(units)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slugs_keep_viewpoints_distinct_and_paths_safe() {
        assert_eq!(slug("box:20k"), "box_20k");
        assert_eq!(viewpoint_slug("+x+y-z"), "pxpymz");
        assert_ne!(viewpoint_slug("+x"), viewpoint_slug("-x"));
        assert_eq!(slug("gator-pt"), "gator-pt");
        assert_eq!(
            slug("variant=linear;sort=radix"),
            "variant_linear_sort_radix"
        );
        assert_eq!(slug("../etc"), ".._etc");
        assert_eq!(slug(".."), "_..");
    }

    #[test]
    fn labels() {
        assert_eq!(dataset_label("spx"), "spx");
        assert_eq!(dataset_label("/data/x/spx.vtk"), "spx.vtk");
    }
}
