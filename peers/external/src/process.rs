//! One external renderer process: started in a process group of its own, spoken to one JSON
//! line at a time, every answer awaited with a timeout, and killed (the whole group) when it
//! hangs, crashes or breaks the protocol.
//!
//! stdout is read by a thread that forwards each line over a channel, so a reply can be
//! awaited with `recv_timeout` (a blocking `read_line` could wait forever on a hung process).
//! stderr is read by another thread into a ring buffer of its last lines, shown in errors.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Write};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde_json::Value;

/// stderr lines kept for error messages.
pub const STDERR_TAIL_LINES: usize = 20;

/// How long a process may take to exit after `shutdown` before its group is killed.
pub const SHUTDOWN_GRACE: Duration = Duration::from_secs(2);

/// Why an exchange failed.
#[derive(Debug, Clone, PartialEq)]
pub enum Failure {
    /// The renderer answered `{"type": "error"}`: the process is fine, the request was not.
    Reported(String),
    /// The process hung, crashed or broke the protocol; it has been killed.
    Broken(String),
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Failure::Reported(m) | Failure::Broken(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for Failure {}

/// A running renderer.
pub struct Process {
    /// The renderer's name in messages (`mine`, `vtk-pt`).
    label: String,
    child: Child,
    stdin: Option<ChildStdin>,
    lines: Receiver<String>,
    stderr_tail: Arc<Mutex<VecDeque<String>>>,
    alive: bool,
    /// The group was killed and the process reaped (killing twice could hit a reused id).
    killed: bool,
}

/// Splits a command line as a POSIX shell would (quotes, backslashes; no expansion).
pub fn split_command(command: &str) -> anyhow::Result<Vec<String>> {
    let argv = shlex::split(command).ok_or_else(|| {
        anyhow::anyhow!("cannot split the command {command:?} (unbalanced quote?)")
    })?;
    if argv.is_empty() {
        anyhow::bail!("the command is empty");
    }
    Ok(argv)
}

impl Process {
    /// Starts `argv` with piped stdin/stdout/stderr and `env` added to tetbench's environment.
    pub fn spawn(
        label: &str,
        argv: &[String],
        env: &[(String, String)],
    ) -> anyhow::Result<Process> {
        let (program, args) = argv
            .split_first()
            .ok_or_else(|| anyhow::anyhow!("{label}: the command is empty"))?;
        let mut cmd = Command::new(program);
        cmd.args(args)
            .envs(env.iter().map(|(k, v)| (k, v)))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        // A group of its own, so that killing it also ends whatever it started (a shell
        // script's interpreter, a renderer's helper processes).
        #[cfg(unix)]
        {
            use std::os::unix::process::CommandExt;
            cmd.process_group(0);
        }
        let mut child = cmd
            .spawn()
            .map_err(|e| anyhow::anyhow!("{label}: cannot start {:?}: {e}", argv.join(" ")))?;
        let stdout = child.stdout.take().expect("piped stdout");
        let stderr = child.stderr.take().expect("piped stderr");
        let (tx, lines) = mpsc::channel();
        std::thread::Builder::new()
            .name(format!("{label}-stdout"))
            .spawn(move || {
                for line in BufReader::new(stdout).lines() {
                    let Ok(line) = line else { break };
                    if tx.send(line).is_err() {
                        break;
                    }
                }
            })
            .map_err(|e| anyhow::anyhow!("{label}: cannot start a reader thread: {e}"))?;
        let stderr_tail = Arc::new(Mutex::new(VecDeque::with_capacity(STDERR_TAIL_LINES)));
        let tail = Arc::clone(&stderr_tail);
        std::thread::Builder::new()
            .name(format!("{label}-stderr"))
            .spawn(move || {
                for line in BufReader::new(stderr).lines() {
                    let Ok(line) = line else { break };
                    let mut t = tail.lock().unwrap_or_else(|p| p.into_inner());
                    if t.len() == STDERR_TAIL_LINES {
                        t.pop_front();
                    }
                    t.push_back(line);
                }
            })
            .map_err(|e| anyhow::anyhow!("{label}: cannot start a reader thread: {e}"))?;
        Ok(Process {
            label: label.to_string(),
            stdin: child.stdin.take(),
            child,
            lines,
            stderr_tail,
            alive: true,
            killed: false,
        })
    }

    /// Whether the process is still usable (not killed after a failure, not exited).
    pub fn is_alive(&mut self) -> bool {
        if self.alive && matches!(self.child.try_wait(), Ok(Some(_))) {
            self.alive = false;
        }
        self.alive
    }

    /// The last lines the process wrote to stderr, oldest first.
    pub fn stderr_tail(&self) -> Vec<String> {
        // The reader thread may still be taking in the lines a dying process wrote last.
        std::thread::sleep(Duration::from_millis(50));
        self.stderr_tail
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .iter()
            .cloned()
            .collect()
    }

    fn with_stderr(&self, msg: String) -> String {
        let tail = self.stderr_tail();
        if tail.is_empty() {
            format!("{msg} (it wrote nothing to stderr)")
        } else {
            format!("{msg}; its last stderr lines:\n    {}", tail.join("\n    "))
        }
    }

    /// Kills the process group and reaps the process.
    pub fn kill(&mut self) {
        if self.killed {
            return;
        }
        self.killed = true;
        #[cfg(unix)]
        {
            // SAFETY: kill(2) with a negative pid signals the group the child leads
            // (process_group(0) made its pid the group id); no memory is touched.
            unsafe {
                libc::kill(-(self.child.id() as i32), libc::SIGKILL);
            }
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.stdin = None;
        self.alive = false;
    }

    fn broken(&mut self, msg: String) -> Failure {
        self.kill();
        Failure::Broken(self.with_stderr(msg))
    }

    /// Sends `request` (its `type` names it in messages) and waits up to `timeout` for the
    /// reply, which must be an object of type `expect` (or an error reply).
    pub fn exchange(
        &mut self,
        request: &Value,
        expect: &str,
        timeout: Duration,
    ) -> Result<Value, Failure> {
        let what = request["type"].as_str().unwrap_or("?").to_string();
        let label = self.label.clone();
        if !self.is_alive() {
            let status = self.child.try_wait().ok().flatten();
            return Err(Failure::Broken(self.with_stderr(format!(
                "{label} is not running (exit status {})",
                status.map_or("unknown".into(), |s| s.to_string())
            ))));
        }
        let mut text = serde_json::to_string(request).expect("a JSON value serialises");
        text.push('\n');
        let written = match self.stdin.as_mut() {
            Some(stdin) => stdin.write_all(text.as_bytes()).and_then(|_| stdin.flush()),
            None => Err(std::io::Error::other("stdin closed")),
        };
        if let Err(e) = written {
            let status = self.wait_briefly();
            return Err(self.broken(format!(
                "{label} stopped reading its stdin before `{what}` ({e}; exit status {status})"
            )));
        }
        let started = Instant::now();
        let line = loop {
            let left = timeout.saturating_sub(started.elapsed());
            match self.lines.recv_timeout(left) {
                // Blank lines carry nothing; the protocol's lines are never blank.
                Ok(line) if line.trim().is_empty() => continue,
                Ok(line) => break line,
                Err(RecvTimeoutError::Timeout) => {
                    return Err(self.broken(format!(
                        "{label} did not answer `{what}` within {:.0} s (hung?); tetbench \
                         stopped it",
                        timeout.as_secs_f64()
                    )));
                }
                Err(RecvTimeoutError::Disconnected) => {
                    let status = self.wait_briefly();
                    return Err(self.broken(format!(
                        "{label} exited ({status}) while tetbench waited for the answer to \
                         `{what}`"
                    )));
                }
            }
        };
        let reply: Value = match serde_json::from_str(line.trim()) {
            Ok(v @ Value::Object(_)) => v,
            _ => {
                let shown: String = line.chars().take(200).collect();
                return Err(self.broken(format!(
                    "{label} answered `{what}` with a line that is not a JSON object: {shown:?} \
                     (stdout carries the protocol only; print anything else to stderr)"
                )));
            }
        };
        match reply["type"].as_str() {
            Some(t) if t == expect => Ok(reply),
            Some("error") => Err(Failure::Reported(format!(
                "{label} reported an error for `{what}`: {}",
                reply["message"].as_str().unwrap_or("(no message)")
            ))),
            other => {
                let got = other.map_or("no type".to_string(), |t| format!("type {t:?}"));
                Err(self.broken(format!(
                    "{label} answered `{what}` with {got}, expected type {expect:?} or \"error\""
                )))
            }
        }
    }

    /// The exit status after waiting a moment for it, as text.
    fn wait_briefly(&mut self) -> String {
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_millis(500) {
            if let Ok(Some(status)) = self.child.try_wait() {
                return status.to_string();
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        "still running".into()
    }

    /// Asks the process to exit (`shutdown`), then kills its group if it has not.
    pub fn shutdown(&mut self) {
        if self.is_alive() {
            let _ = self.exchange(
                &serde_json::json!({"type": "shutdown"}),
                "bye",
                SHUTDOWN_GRACE,
            );
            self.stdin = None;
            let t0 = Instant::now();
            while t0.elapsed() < SHUTDOWN_GRACE {
                if let Ok(Some(_)) = self.child.try_wait() {
                    break;
                }
                std::thread::sleep(Duration::from_millis(10));
            }
        }
        // Also ends anything the renderer left running in its group.
        self.kill();
    }
}

impl Drop for Process {
    fn drop(&mut self) {
        self.shutdown();
    }
}
