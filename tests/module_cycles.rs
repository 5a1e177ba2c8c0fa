//! No import cycle between the modules of any crate (issue 14): `scripts/module_cycles.py`
//! reads each crate's `src/` (`use crate::…` and `crate::…::` paths, folder modules as one
//! node) and prints the cycles of the library code and of the code with its tests; every count
//! must be 0. A new cycle fails here with the script's listing of it.

use std::path::Path;
use std::process::Command;

const CRATES: [&str; 11] = [
    "datasets/src",
    "renderers/core/src",
    "renderers/reference/src",
    "renderers/gator-pt/src",
    "renderers/havs/src",
    "renderers/fragment-pt/src",
    "renderers/raycast/src",
    "renderers/splat/src",
    "peers/vtk/src",
    "peers/external/src",
    "harness/src",
];

#[test]
fn no_crate_has_an_import_cycle() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    for dir in CRATES {
        let out = Command::new("python3")
            .arg(root.join("scripts/module_cycles.py"))
            .arg(root.join(dir))
            .output()
            .expect("python3 runs scripts/module_cycles.py (install python3)");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{dir}: {text}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let counts: Vec<&str> = text
            .lines()
            .filter(|l| l.trim().starts_with("cycles:"))
            .collect();
        assert_eq!(
            counts.len(),
            2,
            "{dir}: expected the library and test graphs:\n{text}"
        );
        for c in counts {
            assert_eq!(c.trim(), "cycles: 0", "{dir} has an import cycle:\n{text}");
        }
    }
}
