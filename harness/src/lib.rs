//! The tetbench harness: the run loop over data sets × algorithm variants × viewpoints, image
//! metrics against the exact reference, result files, reports and analyses. The `tetbench`
//! binary (`src/main.rs`) is a thin wrapper around [`cli`].

pub mod algorithms;
pub mod analyze;
pub mod calibrate;
pub mod calibrate_work;
pub mod cli;
pub mod datasets_cmd;
pub mod external_cmd;
pub mod html;
pub mod machine;
pub mod metrics;
pub mod names;
pub mod papers;
pub mod plan;
pub mod plot;
pub mod plot_cli;
pub mod regress;
// The regression wing's modules keep their crate-level paths (`crate::compare`, …).
pub use regress::{compare, compare_plot, compare_report, compare_time, export, history};
pub mod report;
pub mod reproduce;
pub mod results;
pub mod run;
pub mod samples;
pub mod shard;
pub mod stats;
pub mod suite;
pub mod suspect;
