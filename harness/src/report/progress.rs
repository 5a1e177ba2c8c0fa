//! Progress of the long commands (`run`, `reproduce`, `ab`, `bisect`, `calibrate`): an
//! indicatif bar with the elapsed time and an ETA on a terminal, plain lines otherwise (CI
//! logs, pipes), each line with its count and the ETA.
//!
//! The ETA is linear in the steps done (elapsed / done × left): exact for steps of equal size
//! (rows, A/B rounds, benchmarks), a rough guide where they differ (a paper's runs, bisect's
//! steps). A command that runs another command with a bar of its own (`reproduce` runs `run`,
//! `bisect` runs `ab`) reports its own steps as lines only ([`Progress::lines`]), so that one
//! bar is on screen at a time.

use std::io::IsTerminal as _;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// A count of steps of one command, shown as a bar or as lines.
pub struct Progress {
    bar: Option<ProgressBar>,
    /// `tetbench ab: ` or empty: the start of every plain line.
    prefix: String,
    done: u64,
    total: u64,
    started: Instant,
}

/// `1h 02m`, `3m 20s`, `12s`: durations as the lines show them.
pub fn short_duration(d: Duration) -> String {
    let s = d.as_secs();
    match s {
        0..60 => format!("{s}s"),
        60..3600 => format!("{}m {:02}s", s / 60, s % 60),
        _ => format!("{}h {:02}m", s / 3600, s / 60 % 60),
    }
}

impl Progress {
    /// A bar on a terminal (stderr), plain lines otherwise. `command` starts every plain line
    /// (`tetbench ab`; empty for none), `unit` names the steps on the bar (`rows`, `rounds`).
    pub fn new(command: &str, total: u64, unit: &str) -> Progress {
        let bar = std::io::stderr().is_terminal().then(|| {
            let b = ProgressBar::new(total);
            b.set_style(
                ProgressStyle::with_template(&format!(
                    "{{elapsed_precise}} [{{bar:30}}] {{pos}}/{{len}} {unit}  ETA {{eta}}  {{msg}}"
                ))
                .expect("valid template")
                .progress_chars("=> "),
            );
            b
        });
        Progress {
            bar,
            ..Progress::lines(command, total)
        }
    }

    /// Plain lines only, also on a terminal: for a command whose steps run another command
    /// that shows a bar.
    pub fn lines(command: &str, total: u64) -> Progress {
        Progress {
            bar: None,
            prefix: if command.is_empty() {
                String::new()
            } else {
                format!("{command}: ")
            },
            done: 0,
            total,
            started: Instant::now(),
        }
    }

    /// The time left at the rate so far; `None` before the first step.
    pub fn eta(&self) -> Option<Duration> {
        (self.done > 0).then(|| {
            let per = self.started.elapsed().as_secs_f64() / self.done as f64;
            Duration::from_secs_f64(per * self.total.saturating_sub(self.done) as f64)
        })
    }

    /// `[3/12, ETA 1m 20s]` (no ETA before the first step or after the last).
    fn count(&self) -> String {
        match self.eta().filter(|_| self.done < self.total) {
            Some(eta) => format!(
                "[{}/{}, ETA {}]",
                self.done,
                self.total,
                short_duration(eta)
            ),
            None => format!("[{}/{}]", self.done, self.total),
        }
    }

    /// The next step starts: the bar's message, or a line with the step's number and the ETA
    /// (`bisect: [2/5, ETA 3m 00s] abc123 …`).
    pub fn begin(&self, what: &str) {
        match &self.bar {
            Some(b) => b.set_message(what.to_string()),
            None => {
                let eta = self
                    .eta()
                    .map(|e| format!(", ETA {}", short_duration(e)))
                    .unwrap_or_default();
                eprintln!(
                    "{}[{}/{}{eta}] {what}",
                    self.prefix,
                    self.done + 1,
                    self.total
                );
            }
        }
    }

    /// What is happening now: the bar's message, or a line.
    pub fn status(&self, msg: &str) {
        match &self.bar {
            Some(b) => b.set_message(msg.to_string()),
            None => eprintln!("{}{msg}", self.prefix),
        }
    }

    /// What is being measured, on the bar only (line mode prints one line per step).
    pub fn activity(&self, msg: &str) {
        if let Some(b) = &self.bar {
            b.set_message(msg.to_string());
        }
    }

    /// A line above the bar, or a plain line.
    pub fn log(&self, line: &str) {
        match &self.bar {
            Some(b) => b.println(line),
            None => eprintln!("{line}"),
        }
    }

    /// One step done, described by `line`.
    pub fn step(&mut self, line: &str) {
        self.done += 1;
        match &self.bar {
            Some(b) => {
                b.println(line);
                b.inc(1);
            }
            None => eprintln!("{}{} {line}", self.prefix, self.count()),
        }
    }

    /// `n` steps that need no work (resumed, cached).
    pub fn skip(&mut self, n: u64) {
        self.done += n;
        if let Some(b) = &self.bar {
            b.inc(n);
        }
    }

    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_and_counts() {
        assert_eq!(short_duration(Duration::from_secs(12)), "12s");
        assert_eq!(short_duration(Duration::from_secs(200)), "3m 20s");
        assert_eq!(short_duration(Duration::from_secs(3720)), "1h 02m");
        let mut p = Progress::lines("tetbench x", 4);
        assert_eq!(p.count(), "[0/4]");
        assert!(p.eta().is_none());
        p.started = Instant::now() - Duration::from_secs(10);
        p.done = 1;
        // 10 s for one step, three left: 30 s.
        let eta = p.eta().unwrap().as_secs_f64();
        assert!((29.0..31.0).contains(&eta), "{eta}");
        assert!(p.count().starts_with("[1/4, ETA "), "{}", p.count());
        p.done = 4;
        assert_eq!(p.count(), "[4/4]");
    }
}
