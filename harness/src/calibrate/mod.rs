//! `tetbench calibrate`: a short, fixed micro-benchmark of the backend, and the roofline every
//! row gets from it. The benchmark is a table of named probes ([`probes::PROBES`]); the same
//! probes, timed beside every run's rows, are the run's control ([`control`]), which prices each
//! row's roofline with the machine of its own moment.
//!
//! The figures, each from one kernel that stresses one resource (`calibrate.wgsl`):
//! small-triangle setup rate (triangles covering one pixel each), fill rate (a viewport-sized
//! triangle blended additively into the target format the algorithms use), rasterisation of
//! triangles that cover pixels (two sizes, fitted as a cost per triangle plus a cost per
//! fragment: small triangles cost far more per fragment than one viewport-sized triangle, and a
//! projected cell's are small), compute throughput
//! (vec4 FMA chains), storage-copy bandwidth (a compute copy between two storage buffers), the
//! CPU radix sort of `render_core::sort` (HAVS §5.1) in keys/s, and the work-specific ones of
//! `work.rs`: ray steps (a walk through 144-byte cells), splat fragments (a compute pass's
//! footprint lookup added into a two-u32 fixed-point sheet) and render-core's GPU radix sort.
//! Each figure is the best of five timed repetitions after one warm-up (a roofline wants the
//! backend's peak, and on a busy machine the best repetition is the one least disturbed), by
//! wall clock around submit-and-wait, so it is comparable with the rows' `total_ms`. The
//! result is cached per adapter, driver and CPU in the reference cache directory, so a run
//! pays for it once (a few seconds on lavapipe).
//!
//! The roofline ([`annotate`]) reads work counters, never names: each [`Resource`] lists the
//! counters that measure a row's work on it (`triangles`, `fragments`, `covering_tets`,
//! `splat_fragments`, `ray_steps`, `cpu_sort_keys`, `gpu_sort_keys`) with the calibrated cost
//! of one unit of each; a row's time on a resource is the sum of its counters times their
//! costs, plus per-frame GPU bytes (scratch, k-buffers, targets: each written at least once a
//! frame) over the copy bandwidth. The largest is the
//! bound (`roofline_ms`, `bound_by`), and `limit_fraction = roofline_ms / total_ms` says how
//! close the row gets to it. `normalized_time = total_ms / roofline_ms` is what
//! `compare --normalised` compares across machines. A renderer gets a meaningful bound by
//! reporting its work under these names (docs/roofline.md). The compute figure is recorded but
//! enters no row's roofline: no renderer reports its arithmetic count, and inventing one would
//! make the bound fiction.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use render_core::Gpu;

use crate::calibrate::probes::{ProbeContext, PROBES};
use crate::report::progress::Progress;
use crate::results::machine::MachineInfo;
use crate::results::{Bound, Row};

pub mod control;
pub mod floor;
pub mod kernels;
pub mod probes;
pub mod work;
pub mod workload;

pub use kernels::raster_fragments_per_triangle;
pub use probes::raster_costs;

/// Bumped whenever a kernel or its size changes (old cache files are then re-measured). 10:
/// the splat fill's filtered-texture variant (9 was a build taken back, whose cache files hold
/// a figure this one does not measure).
pub const CALIBRATION_VERSION: u32 = 10;

pub use crate::results::machine::Calibration;

fn driver_of(gpu: &Gpu) -> String {
    let a = &gpu.adapter;
    format!("{} {}", a.driver, a.driver_info).trim().to_string()
}

/// The cache file of this adapter + driver + CPU (the CPU matters: on lavapipe it *is* the GPU).
pub fn cache_path(cache_dir: &Path, gpu: &Gpu, machine: &MachineInfo) -> PathBuf {
    let key = format!(
        "v{CALIBRATION_VERSION}|{}|{}|{}|{}|{}",
        gpu.adapter.name,
        gpu.adapter.backend,
        driver_of(gpu),
        machine.cpu_model,
        machine.cpu_cores
    );
    let hex = blake3::hash(key.as_bytes()).to_hex();
    cache_dir.join("calibration").join(format!(
        "{}-{}.json",
        crate::results::names::slug(&gpu.adapter.name),
        &hex[..16]
    ))
}

/// The cached calibration if there is one for this backend, else a fresh measurement (then
/// cached). `force` always measures.
pub fn cached_or_measure(
    gpu: &Gpu,
    machine: &MachineInfo,
    cache_dir: &Path,
    force: bool,
) -> anyhow::Result<(Calibration, bool)> {
    let path = cache_path(cache_dir, gpu, machine);
    if !force {
        if let Some(c) = std::fs::read_to_string(&path)
            .ok()
            .and_then(|t| serde_json::from_str::<Calibration>(&t).ok())
            .filter(|c| c.version == CALIBRATION_VERSION)
        {
            return Ok((c, true));
        }
    }
    // A figure is a peak: a new measurement keeps, figure by figure, the faster of itself and
    // the cached one of this same backend (a repetition disturbed by other work on the machine
    // only ever makes a figure slower).
    let cached = std::fs::read_to_string(&path)
        .ok()
        .and_then(|t| serde_json::from_str::<Calibration>(&t).ok())
        .filter(|c| c.version == CALIBRATION_VERSION);
    let measured = measure(gpu, machine)?;
    let c = match &cached {
        Some(old) => measured.peak_with(old),
        None => measured,
    };
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    std::fs::write(&path, serde_json::to_string_pretty(&c)?)
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok((c, false))
}

/// Runs every probe of [`PROBES`] (seconds on an idle lavapipe, well under one on a GPU).
pub fn measure(gpu: &Gpu, machine: &MachineInfo) -> anyhow::Result<Calibration> {
    let started = Instant::now();
    let mut progress = Progress::new("tetbench calibrate", PROBES.len() as u64, "benchmarks");
    let ctx = ProbeContext::new(gpu);
    let mut c = Calibration {
        version: CALIBRATION_VERSION,
        adapter: gpu.adapter.name.clone(),
        driver: driver_of(gpu),
        cpu_model: machine.cpu_model.clone(),
        cpu_cores: machine.cpu_cores,
        date_utc: crate::results::machine::iso8601_utc(std::time::SystemTime::now()),
        seconds: 0.0,
        triangles_per_sec: 0.0,
        fill_fragments_per_sec: 0.0,
        fill_format: format!("{:?}", kernels::fill_format(gpu)),
        compute_gflops: 0.0,
        copy_bytes_per_sec: 0.0,
        sort_keys_per_sec: 0.0,
        ray_steps_per_sec: 0.0,
        splat_fragments_per_sec: 0.0,
        gpu_sort_keys_per_sec: 0.0,
        tet_classifications_per_sec: 0.0,
        raster_seconds_per_triangle: 0.0,
        raster_seconds_per_fragment: 0.0,
    };
    for probe in &PROBES {
        progress.activity(probe.name);
        for (figure, value) in probe.measure(&ctx)? {
            figure.set(&mut c, value);
        }
        progress.step(probe.name);
    }
    progress.finish();
    c.seconds = started.elapsed().as_secs_f64();
    Ok(c)
}

// ---------------------------------------------------------------------------------------------
// Roofline
// ---------------------------------------------------------------------------------------------

/// A work counter's name and the calibrated seconds one unit of that work costs (0 where the
/// calibration did not measure it).
pub type CounterCost = (&'static str, fn(&Calibration) -> f64);

/// One resource of the roofline: the work counters a row reports on it, each at its own cost.
pub struct Resource {
    pub bound: Bound,
    pub costs: &'static [CounterCost],
}

/// Seconds per unit of a rate (0 for a rate not measured).
fn per(rate: f64) -> f64 {
    if rate > 0.0 {
        1.0 / rate
    } else {
        0.0
    }
}

/// What a triangle that yields fragments costs beyond its setup (the rasterisation fit's
/// per-triangle figure less the sub-pixel one).
fn covering_triangle_cost(c: &Calibration) -> f64 {
    (c.raster_seconds_per_triangle - per(c.triangles_per_sec)).max(0.0)
}

/// Every counter-priced resource. A renderer opts in by reporting the counter; nothing here
/// knows which renderer reports what.
pub const RESOURCES: [Resource; 8] = [
    Resource {
        bound: Bound::TriangleSetup,
        costs: &[("triangles", |c| per(c.triangles_per_sec))],
    },
    Resource {
        bound: Bound::Fill,
        costs: &[("fragments", |c| per(c.fill_fragments_per_sec))],
    },
    // Every triangle costs at least its setup (the sub-pixel figure); one that yields fragments
    // costs the fit's per-triangle figure, and each fragment the fit's per-fragment one.
    // `covering_tets` (tets whose projection holds a pixel centre) is a lower bound of the
    // triangles that yield fragments: each such tet draws at least one. `covering_faces`
    // (faces drawn as one triangle each whose projection holds a pixel centre) counts them.
    // Rows without either (and calibrations without the fit) price no triangle above its setup.
    Resource {
        bound: Bound::Rasterisation,
        costs: &[
            ("triangles", |c| {
                if c.raster_seconds_per_fragment > 0.0 || c.raster_seconds_per_triangle > 0.0 {
                    per(c.triangles_per_sec)
                } else {
                    0.0
                }
            }),
            ("covering_tets", covering_triangle_cost),
            ("covering_faces", covering_triangle_cost),
            ("fragments", |c| c.raster_seconds_per_fragment),
        ],
    },
    // `splat_fragments` counts every footprint pixel; early splat elimination skips the
    // lookups and atomics of those behind an opaque pixel (`ese_dropped_fragments`, the GPU's
    // exact count), so they are taken back: a bound must not price work the frame skipped.
    Resource {
        bound: Bound::SplatFill,
        costs: &[
            ("splat_fragments", |c| per(c.splat_fragments_per_sec)),
            ("ese_dropped_fragments", |c| -per(c.splat_fragments_per_sec)),
        ],
    },
    Resource {
        bound: Bound::RaySteps,
        costs: &[("ray_steps", |c| per(c.ray_steps_per_sec))],
    },
    Resource {
        bound: Bound::CpuSort,
        costs: &[("cpu_sort_keys", |c| per(c.sort_keys_per_sec))],
    },
    Resource {
        bound: Bound::GpuSort,
        costs: &[("gpu_sort_keys", |c| per(c.gpu_sort_keys_per_sec))],
    },
    // A resource of its own, not a term of `rasterisation`: a vertex stage's classification
    // may overlap the rasterisation of earlier triangles (llvmpipe bins and rasterises in
    // different threads), so only the larger of the two is a bound.
    Resource {
        bound: Bound::Classification,
        costs: &[(
            "tet_classifications",
            |c| per(c.tet_classifications_per_sec),
        )],
    },
];

/// The time (ms) each modelled resource alone needs for the row's work: each resource whose
/// counters the row reports (and whose rate the calibration has), and the per-frame GPU bytes
/// (scratch, targets: each written at least once a frame) at the copy bandwidth.
pub fn resource_times(row: &Row, cal: &Calibration) -> Vec<(Bound, f64)> {
    let mut t = vec![];
    for r in &RESOURCES {
        let priced: Vec<(f64, f64)> = r
            .costs
            .iter()
            .filter_map(|(counter, cost)| Some((row.counter(counter)?, cost(cal))))
            .filter(|&(_, cost)| cost != 0.0)
            .collect();
        // A negative cost takes back work a positive one counted but the frame skipped; the
        // resource is priced only where some work is counted, and never below 0.
        if priced.iter().any(|&(_, cost)| cost > 0.0) {
            let seconds: f64 = priced.iter().map(|(work, cost)| work * cost).sum();
            t.push((r.bound, seconds.max(0.0) * 1e3));
        }
    }
    if let Some(b) = row.gpu_bytes_frame {
        if cal.copy_bytes_per_sec > 0.0 {
            t.push((Bound::Memory, b as f64 / cal.copy_bytes_per_sec * 1e3));
        }
    }
    t
}

/// Fills each measured row's roofline columns: priced with the control of its own rounds
/// where it has one ([`control::priced`]: the figures of the moment, the rest of `cal` scaled
/// by the control's factor), else with `cal` (results without a control).
pub fn annotate(rows: &mut [Row], cal: &Calibration) {
    for row in rows.iter_mut() {
        if row.total_ms.is_none_or(|t| t <= 0.0) {
            continue;
        }
        let (priced, pricing) = if row.round_control.is_empty() {
            (cal.clone(), control::Pricing::Calibration)
        } else {
            let (c, scaled) = control::priced(cal, &control::row_figures(&row.round_control));
            (c, control::Pricing::Control { scaled })
        };
        let bound = resource_times(row, &priced)
            .into_iter()
            .max_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((resource, ms)) = bound.filter(|b| b.1 > 0.0) {
            row.roofline_ms = Some(ms);
            row.bound_by = Some(resource);
            row.priced_with = pricing;
            set_fraction(row);
        }
    }
}

/// Each row's `control_factor`: its rounds' control against `run_median` (the run's median
/// control), as a speed ratio ([`control::speed_factor`]).
pub fn set_control_factors(rows: &mut [Row], run_median: &control::Figures) {
    for row in rows.iter_mut() {
        row.control_factor = (!row.round_control.is_empty())
            .then(|| control::speed_factor(&control::row_figures(&row.round_control), run_median))
            .flatten();
    }
}

/// Sets `limit_fraction` (roofline / total) and `normalized_time` (its inverse) from the row's
/// `roofline_ms` and `total_ms`: by [`annotate`], and again wherever a row's total changes
/// after it (rounds merged into one row, `ab`), so that the fraction is always the one of the
/// time the row reports.
pub fn set_fraction(row: &mut Row) {
    if let (Some(ms), Some(total)) = (row.roofline_ms, row.total_ms.filter(|t| *t > 0.0)) {
        row.limit_fraction = Some(ms / total);
        row.normalized_time = Some(total / ms);
    }
}

/// Whether the row's fastest timed frame beat its roofline (`roofline_ms > total_ms_min`). A
/// lower bound that a measured frame beats is a defect of the bound (a calibrated figure that
/// is not the backend's peak for that work, or a counter that counts work the frame did not
/// do), never a fast renderer: the run lists such rows.
pub fn beats_bound(row: &Row) -> bool {
    matches!((row.roofline_ms, row.total_ms_min), (Some(bound), Some(fastest)) if bound > fastest)
}

/// `tetbench calibrate`.
pub fn run_command(cache_dir: &Path, force: bool, json: bool) -> anyhow::Result<()> {
    let gpu = Gpu::new()?;
    let machine = MachineInfo::collect();
    let (cal, cached) = cached_or_measure(&gpu, &machine, cache_dir, force)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&cal)?);
    } else {
        println!("{}", cal.describe());
        println!(
            "{} {}",
            if cached { "cached in" } else { "stored in" },
            cache_path(cache_dir, &gpu, &machine).display()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests;
