//! The hook `scripts/profile.sh` uses to profile only the frames and rows of a run: when
//! `TETBENCH_PERF_CONTROL=CTL_FIFO,ACK_FIFO` is set, the run loop tells `perf record -D -1
//! --control fifo:CTL_FIFO,ACK_FIFO` to enable sampling once a data set's variants are prepared,
//! and to disable it when they are done. Loading a mesh or compiling pipelines (seconds on
//! lavapipe) would otherwise fill the profile of a frame that takes milliseconds.
//!
//! Without the variable this does nothing. A broken pipe or a missing FIFO is reported once on
//! stderr and otherwise ignored: profiling must never change a run's results.

use std::fs::{File, OpenOptions};
use std::io::{BufRead, BufReader, Write};

const VARIABLE: &str = "TETBENCH_PERF_CONTROL";

/// Sampling is on while this lives (when the variable is set).
pub struct ProfiledSection {
    control: Option<Control>,
}

struct Control {
    ctl: File,
    ack: BufReader<File>,
}

impl Control {
    fn open(spec: &str) -> std::io::Result<Control> {
        let (ctl, ack) = spec.split_once(',').ok_or_else(|| {
            std::io::Error::other(format!(
                "{VARIABLE} must be CTL_FIFO,ACK_FIFO, not {spec:?}"
            ))
        })?;
        Ok(Control {
            ctl: OpenOptions::new().write(true).open(ctl)?,
            ack: BufReader::new(File::open(ack)?),
        })
    }

    /// Sends one command and waits for perf's `ack`, so no sample of what follows is lost.
    fn send(&mut self, command: &str) -> std::io::Result<()> {
        writeln!(self.ctl, "{command}")?;
        self.ctl.flush()?;
        let mut reply = String::new();
        self.ack.read_line(&mut reply)?;
        Ok(())
    }
}

impl ProfiledSection {
    pub fn begin() -> ProfiledSection {
        let Ok(spec) = std::env::var(VARIABLE) else {
            return ProfiledSection { control: None };
        };
        let control = Control::open(&spec).and_then(|mut c| c.send("enable").map(|()| c));
        match control {
            Ok(c) => ProfiledSection { control: Some(c) },
            Err(e) => {
                eprintln!("tetbench: {VARIABLE}={spec}: cannot reach perf ({e}); not profiling");
                ProfiledSection { control: None }
            }
        }
    }
}

impl Drop for ProfiledSection {
    fn drop(&mut self) {
        if let Some(c) = self.control.as_mut() {
            if let Err(e) = c.send("disable") {
                eprintln!("tetbench: {VARIABLE}: cannot reach perf ({e})");
            }
        }
    }
}
