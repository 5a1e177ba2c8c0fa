//! The tetbench harness: the run loop over data sets × algorithm variants × viewpoints, image
//! metrics against the exact reference, result files, reports and analyses. The `tetbench`
//! binary (`src/main.rs`) is a thin wrapper around [`cli`].
//!
//! One folder per wing (ARCHITECTURE.md, "The harness's wings"); [`algorithms`], the registry
//! every wing reads and the one line an added algorithm touches, is the only loose file.

pub mod algorithms;
pub mod analyze;
pub mod calibrate;
pub mod cli;
pub mod papers;
pub mod plot;
pub mod regress;
pub mod report;
pub mod results;
pub mod run;
pub mod schemas;
