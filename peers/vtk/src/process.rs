//! The persistent Python process that runs VTK: found, started, spoken to (one JSON object per
//! line each way over its stdin/stdout), and stopped.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

use anyhow::{anyhow, bail, Context};
use serde_json::Value;

/// The peer script, embedded so the binary needs nothing beside it but Python and `vtk`.
pub const SCRIPT: &str = include_str!("vtk_peer.py");

/// Environment variable naming the Python interpreter that has the `vtk` package.
pub const PYTHON_ENV: &str = "TETBENCH_VTK_PYTHON";

/// The virtual environment `scripts/setup-vtk.sh` creates at the repository root.
pub const VENV_DIR: &str = ".venv-vtk";

/// How to get a working VTK, appended to every "cannot start" error.
pub const INSTALL_HINT: &str =
    "run scripts/setup-vtk.sh (creates .venv-vtk/ with `pip install vtk` and \
     installs Mesa's EGL for offscreen rendering), or `pip install vtk` into a Python and set \
     TETBENCH_VTK_PYTHON to it";

/// The interpreter to run: `$TETBENCH_VTK_PYTHON`, else `.venv-vtk/bin/python` in the current
/// directory or one above it, or above the running executable (target/release/tetbench), else
/// `python3` from PATH.
pub fn python_interpreter() -> PathBuf {
    if let Some(p) = std::env::var_os(PYTHON_ENV).filter(|p| !p.is_empty()) {
        return PathBuf::from(p);
    }
    let mut starts: Vec<PathBuf> = vec![];
    if let Ok(cwd) = std::env::current_dir() {
        starts.push(cwd);
    }
    if let Some(dir) = std::env::current_exe()
        .ok()
        .and_then(|e| e.parent().map(Path::to_path_buf))
    {
        starts.push(dir);
    }
    for start in starts {
        for dir in start.ancestors() {
            let candidate = dir.join(VENV_DIR).join("bin").join("python");
            if candidate.is_file() {
                return candidate;
            }
        }
    }
    PathBuf::from("python3")
}

/// One running peer script.
pub struct PeerProcess {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
    /// The hello line: VTK and Python versions.
    pub hello: Value,
    /// Keeps the script file alive as long as the process.
    _script_dir: tempfile::TempDir,
}

impl PeerProcess {
    /// Starts the script under [`python_interpreter`] and waits for its hello (which fails
    /// when `vtk` cannot be imported).
    pub fn start() -> anyhow::Result<PeerProcess> {
        let python = python_interpreter();
        let dir = tempfile::Builder::new()
            .prefix("tetbench-vtk-")
            .tempdir()
            .context("cannot create a temporary directory for the VTK peer script")?;
        let script = dir.path().join("vtk_peer.py");
        std::fs::write(&script, SCRIPT)
            .with_context(|| format!("cannot write {}", script.display()))?;
        let mut cmd = Command::new(&python);
        cmd.arg("-u")
            .arg(&script)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit());
        // Offscreen through EGL (Mesa's llvmpipe without a GPU): no X display needed.
        if std::env::var_os("VTK_DEFAULT_OPENGL_WINDOW").is_none() {
            cmd.env("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow");
        }
        let mut child = cmd.spawn().map_err(|e| {
            anyhow!(
                "VTK peer: cannot run {} ({e}); {INSTALL_HINT}",
                python.display()
            )
        })?;
        let stdin = child.stdin.take().expect("piped stdin");
        let stdout = BufReader::new(child.stdout.take().expect("piped stdout"));
        let mut p = PeerProcess {
            child,
            stdin,
            stdout,
            hello: Value::Null,
            _script_dir: dir,
        };
        let hello = p
            .read_reply()
            .map_err(|e| anyhow!("VTK peer under {}: {e:#}; {INSTALL_HINT}", python.display()))?;
        p.hello = hello;
        Ok(p)
    }

    fn read_reply(&mut self) -> anyhow::Result<Value> {
        let mut line = String::new();
        let n = self
            .stdout
            .read_line(&mut line)
            .context("reading the VTK peer's answer")?;
        if n == 0 {
            let status = self.child.wait().ok();
            bail!(
                "the VTK peer process ended without answering (exit status {}; its messages are \
                 on stderr above)",
                status
                    .map(|s| s.to_string())
                    .unwrap_or_else(|| "unknown".into())
            );
        }
        let v: Value = serde_json::from_str(line.trim()).with_context(|| {
            format!("the VTK peer answered something that is not JSON: {line:?}")
        })?;
        if v.get("ok") != Some(&Value::Bool(true)) {
            let msg = v
                .get("error")
                .and_then(Value::as_str)
                .unwrap_or("no reason given");
            bail!("{msg}");
        }
        Ok(v)
    }

    /// Sends one request and returns the answer (an error when the script reports one).
    pub fn request(&mut self, req: &Value) -> anyhow::Result<Value> {
        let mut text = serde_json::to_string(req).expect("a JSON value serialises");
        text.push('\n');
        self.stdin
            .write_all(text.as_bytes())
            .and_then(|_| self.stdin.flush())
            .context("the VTK peer process is gone (writing a request)")?;
        self.read_reply()
    }
}

impl Drop for PeerProcess {
    fn drop(&mut self) {
        let _ = self.stdin.write_all(b"{\"cmd\":\"quit\"}\n");
        let _ = self.stdin.flush();
        // The script exits on quit; give it a moment, then make sure.
        for _ in 0..50 {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
