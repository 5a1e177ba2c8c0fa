//! `tetbench analyze control LABEL=RUN…`: each control figure's median over a run's samples, in
//! several runs side by side, and each run's speed over the first's. Where `analyze medians`
//! shows that fractions moved when the machine changed, this shows which of the machine's
//! resources moved, and by how much: a figure measured on the device's threads (fill, the
//! rasteriser's cost per fragment) slows another way than one measured on a single thread
//! (triangle setup) or on the CPU (the radix sort) when other processes share the cores
//! (docs/roofline.md, "Priced at the moment of the row").

use std::fmt::Write as _;

use anyhow::bail;

use crate::analyze::medians::parse_run;
use crate::results::control::Control;
use crate::results::machine::Figure;
use crate::results::ResultsFile;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Runs to set side by side, each `LABEL=DIR` (a `tetbench run` output directory; its
    /// folder name labels it without `LABEL=`). The first is the one the others are divided by.
    #[arg(required = true)]
    pub runs: Vec<String>,
    /// Also write the Markdown to this file.
    #[arg(long)]
    pub out: Option<std::path::PathBuf>,
}

/// One figure of one run: the median over the samples, and the smallest and largest sample
/// over that median (how much the machine moved within the run).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FigureSpread {
    pub median: f64,
    pub low: f64,
    pub high: f64,
}

/// A run's control figures, each with its spread.
#[derive(Debug, Clone, PartialEq)]
pub struct RunControl {
    pub label: String,
    pub samples: usize,
    pub figures: Vec<(Figure, FigureSpread)>,
}

impl RunControl {
    /// The medians are [`Control::median`]'s, the one every row's control factor is taken
    /// against.
    pub fn of(label: &str, control: &Control) -> RunControl {
        let figures = control
            .median()
            .into_iter()
            .map(|(f, m)| {
                let (lo, hi) = control
                    .samples
                    .iter()
                    .filter_map(|s| s.figures.get(&f).copied())
                    .filter(|v| *v > 0.0)
                    .fold((f64::MAX, 0.0_f64), |(lo, hi), x| (lo.min(x), hi.max(x)));
                let spread = FigureSpread {
                    median: m,
                    low: lo / m,
                    high: hi / m,
                };
                (f, spread)
            })
            .collect();
        RunControl {
            label: label.to_string(),
            samples: control.samples.len(),
            figures,
        }
    }

    fn spread_of(&self, figure: Figure) -> Option<FigureSpread> {
        self.figures
            .iter()
            .find(|(f, _)| *f == figure)
            .map(|(_, s)| *s)
    }
}

/// The Markdown table: one line per figure of the first run (the median, and the samples'
/// range over it), then each later run's speed over the first's — the rate's ratio, or the
/// inverse ratio of a cost, so that under 1 is slower for every figure alike.
pub fn markdown(runs: &[RunControl]) -> String {
    let Some(first) = runs.first() else {
        return String::new();
    };
    let mut md = String::from("| figure |");
    let mut rule = String::from("|---|");
    for r in runs {
        let _ = write!(md, " {} (samples' range) |", r.label);
        rule.push_str("---:|");
    }
    for r in &runs[1..] {
        let _ = write!(md, " speed {} / {} |", r.label, first.label);
        rule.push_str("---:|");
    }
    let _ = writeln!(md, "\n{rule}");
    for (figure, base) in &first.figures {
        let _ = write!(md, "| {} |", figure.name());
        for r in runs {
            let cell = r.spread_of(*figure).map_or("–".to_string(), |s| {
                format!("{:.3e} (×{:.2}–×{:.2})", s.median, s.low, s.high)
            });
            let _ = write!(md, " {cell} |");
        }
        for r in &runs[1..] {
            let cell = r.spread_of(*figure).map_or("–".to_string(), |s| {
                format!("{:.2}", figure.speed(s.median) / figure.speed(base.median))
            });
            let _ = write!(md, " {cell} |");
        }
        md.push('\n');
    }
    md.push('\n');
    for r in runs {
        let _ = writeln!(md, "- {}: {} samples.", r.label, r.samples);
    }
    md
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let mut runs = vec![];
    for arg in &args.runs {
        let (label, dir) = parse_run(arg)?;
        let file = ResultsFile::read(&dir)?;
        let Some(control) = file.control.as_ref().filter(|c| !c.samples.is_empty()) else {
            bail!(
                "{}: the results carry no control (a run from before controls, or one that \
                 ran no round)",
                dir.display()
            );
        };
        runs.push(RunControl::of(&label, control));
    }
    crate::analyze::emit(&markdown(&runs), args.out.as_deref())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::control::ControlSample;

    fn sample(fill: f64, per_fragment: f64) -> ControlSample {
        ControlSample {
            dataset: "box:10k".into(),
            round: 0,
            rows_before: 0,
            at_s: 0.0,
            utc: String::new(),
            seconds: 0.01,
            figures: [
                (Figure::FillFragmentsPerSec, fill),
                (Figure::RasterSecondsPerFragment, per_fragment),
            ]
            .into(),
        }
    }

    fn control(samples: Vec<ControlSample>) -> Control {
        Control {
            probes: vec![],
            setup_seconds: 0.0,
            samples,
        }
    }

    #[test]
    fn a_slower_rate_and_a_larger_cost_both_read_under_one() {
        let idle = RunControl::of(
            "idle",
            &control(vec![
                sample(4e8, 5e-9),
                sample(2e8, 5e-9),
                sample(4e8, 5e-9),
            ]),
        );
        assert_eq!(
            idle.spread_of(Figure::FillFragmentsPerSec),
            Some(FigureSpread {
                median: 4e8,
                low: 0.5,
                high: 1.0
            })
        );
        let busy = RunControl::of("busy", &control(vec![sample(2e8, 1e-8)]));
        let md = markdown(&[idle, busy]);
        assert!(
            md.contains(
                "| fill_fragments_per_sec | 4.000e8 (×0.50–×1.00) | 2.000e8 (×1.00–×1.00) | 0.50 |"
            ),
            "{md}"
        );
        assert!(md.contains("| raster_seconds_per_fragment |"), "{md}");
        assert!(md.contains("×1.00) | 0.50 |\n\n"), "{md}");
        assert!(md.contains("- idle: 3 samples."), "{md}");
    }

    #[test]
    fn a_figure_the_later_run_lacks_reads_a_dash() {
        let idle = RunControl::of("idle", &control(vec![sample(4e8, 5e-9)]));
        let mut lacking = sample(4e8, 0.0);
        lacking.figures.remove(&Figure::RasterSecondsPerFragment);
        let other = RunControl::of("other", &control(vec![lacking]));
        let md = markdown(&[idle, other]);
        assert!(md.contains("| – | – |"), "{md}");
    }
}
