//! One run per output directory at a time.
//!
//! Two `tetbench run --out same` at once used to both succeed while the second's
//! `results.json` replaced the first's rows without a word. A run now holds an
//! advisory lock (`flock` through the `fs4` crate) on `OUT/.tetbench-run.lock` for its whole
//! life, and writes who it is into the file; a second run finds the lock taken and refuses,
//! naming the holder. The kernel drops the lock when the holding process ends, however it
//! ends, so a crashed run never leaves the directory stuck: its file remains, but unlocked,
//! and the next run takes it over.

use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

use anyhow::Context;
use serde::{Deserialize, Serialize};

pub const LOCK_FILE: &str = ".tetbench-run.lock";

/// Who holds the lock (the file's content).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Holder {
    pub pid: u32,
    pub host: String,
    pub started_utc: String,
    pub command_line: Vec<String>,
}

/// Held while the run writes into its directory; dropping it releases the lock.
#[derive(Debug)]
pub struct OutputLock {
    _file: File,
    pub path: PathBuf,
}

/// Takes `dir`'s lock (creating `dir`), or refuses naming the run that holds it.
pub fn acquire(dir: &Path, command_line: &[String]) -> anyhow::Result<OutputLock> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let path = dir.join(LOCK_FILE);
    // Never truncated before the lock is ours: the holder's record must stay readable.
    let mut file = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .with_context(|| format!("cannot open {}", path.display()))?;
    // Fully qualified: std's own `File::try_lock` (Rust 1.89) is newer than the workspace's
    // minimum Rust.
    match fs4::FileExt::try_lock(&file) {
        Ok(()) => {}
        Err(fs4::TryLockError::WouldBlock) => {
            let mut text = String::new();
            file.read_to_string(&mut text).ok();
            let who = match serde_json::from_str::<Holder>(&text) {
                Ok(h) => format!(
                    "pid {} on {} since {} ({})",
                    h.pid,
                    h.host,
                    h.started_utc,
                    h.command_line.join(" ")
                ),
                Err(_) => "a process that has not yet said who it is".into(),
            };
            anyhow::bail!(
                "{} is in use by another tetbench run: {who}. Two runs into one directory would \
                 overwrite each other's results; wait for it to finish or choose another --out \
                 (lock file {})",
                dir.display(),
                path.display()
            );
        }
        Err(fs4::TryLockError::Error(e)) => {
            return Err(e).with_context(|| format!("cannot lock {}", path.display()))
        }
    }
    let holder = Holder {
        pid: std::process::id(),
        host: crate::results::machine::host_name(),
        started_utc: crate::results::machine::iso8601_utc(std::time::SystemTime::now()),
        command_line: command_line.to_vec(),
    };
    file.set_len(0)?;
    file.rewind()?;
    file.write_all(serde_json::to_string(&holder)?.as_bytes())
        .and_then(|_| file.flush())
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(OutputLock { _file: file, path })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `acquire`, retried for up to two seconds. flock's lock belongs to the open file, and a
    /// test running beside this one that starts a process (git, a browser) copies every
    /// descriptor into its child between fork and exec (close-on-exec drops them at exec): for
    /// that moment a released lock is still held. A run never forks while it takes its lock;
    /// the tests do.
    fn acquire_soon(dir: &Path, command_line: &[String]) -> OutputLock {
        for _ in 0..200 {
            if let Ok(lock) = acquire(dir, command_line) {
                return lock;
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        acquire(dir, command_line).unwrap()
    }

    /// A second lock on a held directory is refused with the holder named; once released, and
    /// over a stale file left by a crashed run (a dead pid, no lock held), it is granted.
    #[test]
    fn a_held_directory_refuses_and_a_stale_file_does_not_block() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out");
        let first = acquire_soon(&dir, &["tetbench".into(), "run".into()]);
        let e = acquire(&dir, &[]).unwrap_err().to_string();
        let pid = format!("pid {}", std::process::id());
        assert!(e.contains(&pid), "{e}");
        assert!(e.contains(&crate::results::machine::host_name()), "{e}");
        assert!(e.contains("tetbench run"), "{e}");
        drop(first);
        let again = acquire_soon(&dir, &[]);
        drop(again);
        // What a crashed run leaves: its record, but no lock.
        let stale = Holder {
            pid: u32::MAX - 1,
            host: crate::results::machine::host_name(),
            started_utc: "2000-01-01T00:00:00Z".into(),
            command_line: vec!["tetbench".into()],
        };
        std::fs::write(dir.join(LOCK_FILE), serde_json::to_string(&stale).unwrap()).unwrap();
        let taken = acquire_soon(&dir, &["new".into()]);
        let now: Holder =
            serde_json::from_str(&std::fs::read_to_string(&taken.path).unwrap()).unwrap();
        assert_eq!(now.pid, std::process::id());
        assert_eq!(now.command_line, ["new"]);
    }
}
