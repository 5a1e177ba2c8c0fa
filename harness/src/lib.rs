//! The tetbench harness: the run loop over data sets × algorithm variants × viewpoints, image
//! metrics against the exact reference, result files, reports and analyses. The `tetbench`
//! binary (`src/main.rs`) is a thin wrapper around [`cli`].

pub mod algorithms;
pub mod analyze;
pub mod calibrate;
pub mod calibrate_work;
pub mod cli;
pub mod compare;
pub mod compare_plot;
pub mod compare_report;
pub mod compare_time;
pub mod datasets_cmd;
pub mod export;
pub mod external_cmd;
pub mod history;
pub mod html;
pub mod machine;
pub mod metrics;
pub mod names;
pub mod papers;
pub mod plan;
pub mod plot;
pub mod plot_cli;
pub mod regress;
pub mod report;
pub mod reproduce;
pub mod results;
pub mod run;
pub mod samples;
pub mod shard;
pub mod stats;
pub mod suite;
pub mod suspect;
