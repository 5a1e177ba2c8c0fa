//! Where VTK's Python is: the interpreter that runs the embedded peer script.

use std::path::{Path, PathBuf};

/// The peer script (protocol version 1), embedded so the binary needs nothing beside it but
/// Python and `vtk`.
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
