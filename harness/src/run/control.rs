//! The control beside the rows ([`crate::calibrate::control`]): when the run loop takes a
//! sample, and each row's rounds' control once every row is in.

use std::time::Instant;

use crate::calibrate::control::{Control, ControlBench, INTERVAL_S};
use crate::calibrate::probes::ProbeContext;
use crate::report::progress::Progress;
use crate::results::{ResultsWriter, Row};

/// The prepared control probes of a run and when the last sample was taken.
pub struct RunControl<'g> {
    bench: ControlBench<'g>,
    setup_seconds: f64,
    started: Instant,
    last: Option<Instant>,
}

impl<'g> RunControl<'g> {
    pub fn new(probes: &ProbeContext<'g>, started: Instant) -> RunControl<'g> {
        let t0 = Instant::now();
        let bench = ControlBench::new(probes);
        RunControl {
            bench,
            setup_seconds: t0.elapsed().as_secs_f64(),
            started,
            last: None,
        }
    }

    /// Whether [`INTERVAL_S`] has passed since the last sample.
    pub fn due(&self) -> bool {
        self.last
            .is_none_or(|t| t.elapsed().as_secs_f64() >= INTERVAL_S)
    }

    /// Takes a sample before `round` of `dataset` (the number of rounds: after the last) and
    /// adds it to the results.
    pub fn take(
        &mut self,
        dataset: &str,
        round: u32,
        writer: &mut ResultsWriter,
        progress: &Progress,
    ) {
        progress.activity(&format!("control ({dataset}, round {round})"));
        let at_s = self.started.elapsed().as_secs_f64();
        let sample = self
            .bench
            .sample(dataset, round, writer.file.rows.len(), at_s);
        self.last = Some(Instant::now());
        let probes = self.bench.probe_names();
        writer
            .file
            .control
            .get_or_insert_with(|| Control {
                probes,
                setup_seconds: self.setup_seconds,
                samples: vec![],
            })
            .samples
            .push(sample);
    }
}

/// Gives every row measured in this run (rows `--resume` kept have theirs) the control of each
/// of its rounds, and its `control_factor` against the run's median control.
pub fn attach(rows: &mut [Row], control: &Control, rounds: u32) {
    for (i, row) in rows.iter_mut().enumerate() {
        if row.round_control.is_empty() && row.total_ms.is_some() {
            row.round_control = control.rounds_of(&row.dataset, rounds, i);
        }
    }
    crate::calibrate::set_control_factors(rows, &control.median());
}
