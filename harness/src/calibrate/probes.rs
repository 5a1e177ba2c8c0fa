//! The calibration as a table of named probes ([`PROBES`]). A probe prepares one or more
//! [`Workload`]s — the same kernel in a few configurations (sizes, layouts) — and turns their
//! timings into figures of the [`Calibration`]: the fastest configuration's rate, or the
//! rasterisation's fit of a cost per triangle and per fragment.
//!
//! Two users time the same workloads: `tetbench calibrate` (every configuration, best of
//! several repetitions after a warm-up: the backend's peak, cached per adapter) and the
//! control measured beside every run's rows ([`crate::calibrate::control`]: the probes the
//! roofline prices, once each, at the moment of the rows).

use anyhow::Context;

use crate::calibrate::kernels;
pub use crate::calibrate::workload::{ProbeContext, Timing, Workload};
use crate::results::machine::Figure;

/// How a probe's timings become figures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Combine {
    /// One figure: the fastest configuration's rate (a roofline wants the peak at every size
    /// a row works at).
    Fastest,
    /// The rasterisation's two figures: the straight line `t = a + f·b` through (fragments per
    /// triangle, seconds per triangle) of the two leg lengths ([`raster_costs`]).
    RasterFit,
}

/// A named probe of the backend: which figures it measures, how it is prepared, and how its
/// timings combine.
pub struct Probe {
    pub name: &'static str,
    pub figures: &'static [Figure],
    pub prepare: for<'g> fn(&ProbeContext<'g>) -> anyhow::Result<Vec<Workload<'g>>>,
    pub combine: Combine,
    /// Timed repetitions per configuration in the calibration (after one warm-up).
    pub reps: usize,
    /// Whether the control beside the rows measures it: every figure the roofline prices.
    pub in_control: bool,
}

impl Probe {
    /// The figures from one timing per configuration (in the order `prepare` gave them).
    pub fn figures_of(&self, timings: &[Timing]) -> Vec<(Figure, f64)> {
        match self.combine {
            Combine::Fastest => {
                let best = timings.iter().map(Timing::rate).fold(0.0, f64::max);
                vec![(self.figures[0], best)]
            }
            Combine::RasterFit => {
                let points: Vec<(f64, f64)> = timings
                    .iter()
                    .map(|t| (t.param, t.seconds / t.units.max(1.0)))
                    .collect();
                let [small, large] = points[..] else {
                    return vec![];
                };
                let (per_triangle, per_fragment) = raster_costs(small, large);
                vec![
                    (Figure::RasterSecondsPerTriangle, per_triangle),
                    (Figure::RasterSecondsPerFragment, per_fragment),
                ]
            }
        }
    }

    /// Prepares the probe and times every configuration, best of `reps` after one warm-up.
    pub fn measure(&self, ctx: &ProbeContext) -> anyhow::Result<Vec<(Figure, f64)>> {
        let mut timings = vec![];
        for mut w in (self.prepare)(ctx).with_context(|| format!("preparing {}", self.name))? {
            let seconds = best_seconds_of(self.reps, || w.run())
                .with_context(|| format!("running {}", self.name))?;
            timings.push(Timing {
                units: w.units,
                param: w.param,
                seconds,
            });
        }
        Ok(self.figures_of(&timings))
    }
}

/// Timed repetitions after one warm-up (the best is kept: a roofline wants the backend's peak,
/// and on a busy machine the best repetition is the one least disturbed).
pub const REPS: usize = 5;

/// Best seconds of `reps` runs of `f` after one warm-up. A short benchmark is better run
/// often: on a busy machine a short run finds an undisturbed moment more easily than a long
/// one, and the rows it prices are short frames that find them too.
pub fn best_seconds_of(
    reps: usize,
    mut f: impl FnMut() -> anyhow::Result<()>,
) -> anyhow::Result<f64> {
    f()?;
    let mut best = f64::INFINITY;
    for _ in 0..reps.max(1) {
        let t0 = std::time::Instant::now();
        f()?;
        best = best.min(t0.elapsed().as_secs_f64());
    }
    Ok(best.max(1e-9))
}

/// The straight line `t = a + f·b` through two (fragments per triangle, seconds per triangle)
/// points: `(a, b)`, the cost of a triangle and of each of its fragments. Each is at least 0,
/// since timing noise can tilt a two-point fit.
pub fn raster_costs(small: (f64, f64), large: (f64, f64)) -> (f64, f64) {
    let per_fragment = ((large.1 - small.1) / (large.0 - small.0)).max(0.0);
    let per_triangle = (small.1 - small.0 * per_fragment).max(0.0);
    (per_triangle, per_fragment)
}

/// Every probe, in the order `tetbench calibrate` runs them. The compute figure enters no
/// row's roofline (no renderer reports an arithmetic count), so the control leaves it out.
pub const PROBES: [Probe; 10] = [
    Probe {
        name: "triangle setup",
        figures: &[Figure::TrianglesPerSec],
        prepare: kernels::triangle_setup,
        combine: Combine::Fastest,
        reps: REPS,
        in_control: true,
    },
    Probe {
        name: "fill",
        figures: &[Figure::FillFragmentsPerSec],
        prepare: kernels::fill,
        combine: Combine::Fastest,
        reps: REPS,
        in_control: true,
    },
    Probe {
        name: "rasterisation",
        figures: &[
            Figure::RasterSecondsPerTriangle,
            Figure::RasterSecondsPerFragment,
        ],
        prepare: kernels::rasterisation,
        combine: Combine::RasterFit,
        reps: REPS,
        in_control: true,
    },
    Probe {
        name: "compute",
        figures: &[Figure::ComputeGflops],
        prepare: kernels::compute,
        combine: Combine::Fastest,
        reps: REPS,
        in_control: false,
    },
    Probe {
        name: "storage copy",
        figures: &[Figure::CopyBytesPerSec],
        prepare: kernels::storage_copy,
        combine: Combine::Fastest,
        reps: REPS,
        in_control: true,
    },
    Probe {
        name: "CPU radix sort",
        figures: &[Figure::SortKeysPerSec],
        prepare: kernels::cpu_sort,
        combine: Combine::Fastest,
        reps: REPS,
        in_control: true,
    },
    Probe {
        name: "ray steps",
        figures: &[Figure::RayStepsPerSec],
        prepare: crate::calibrate::work::ray_steps,
        combine: Combine::Fastest,
        reps: REPS,
        in_control: true,
    },
    Probe {
        name: "splat fill",
        figures: &[Figure::SplatFragmentsPerSec],
        prepare: crate::calibrate::work::splat_fill,
        combine: Combine::Fastest,
        reps: REPS,
        in_control: true,
    },
    Probe {
        name: "GPU radix sort",
        figures: &[Figure::GpuSortKeysPerSec],
        prepare: crate::calibrate::work::gpu_sort,
        combine: Combine::Fastest,
        reps: REPS,
        in_control: true,
    },
    // A pass as long as a small mesh's, run often (see `best_seconds_of`).
    Probe {
        name: "vertex classification",
        figures: &[Figure::TetClassificationsPerSec],
        prepare: crate::calibrate::work::classification,
        combine: Combine::Fastest,
        reps: 25,
        in_control: true,
    },
];
