//! Every chart is drawn under `harness/src/plot/`: no other module of the
//! harness uses plotters, and no colour is defined outside `plot/style.rs`, the one palette.
//! Callers elsewhere (history, compare, the papers) pass data to a `plot` module. A grep, so it
//! can fail: the second test feeds it what the drawing code it replaced looked like.

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The lines of `text`, a file at `path` relative to `harness/src`, that draw or define a colour
/// where they should not: `plotters::` outside `plot/`, `RGBColor(` outside `plot/style.rs`.
fn offending_lines(path: &str, text: &str) -> Vec<String> {
    let path = path.replace('\\', "/");
    let in_plot = path.starts_with("plot/");
    let is_palette = path == "plot/style.rs";
    text.lines()
        .enumerate()
        .filter(|(_, line)| !line.trim_start().starts_with("//"))
        .filter(|(_, line)| {
            (!in_plot && line.contains("plotters::")) || (!is_palette && line.contains("RGBColor("))
        })
        .map(|(i, line)| format!("{path}:{}: {}", i + 1, line.trim()))
        .collect()
}

#[test]
fn plotters_and_colours_live_under_plot() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = vec![];
    rust_files(&src, &mut files);
    assert!(files.len() > 50, "found only {} files", files.len());
    let mut found = vec![];
    for f in files {
        let rel = f.strip_prefix(&src).unwrap().to_string_lossy().into_owned();
        let text = std::fs::read_to_string(&f).unwrap();
        found.extend(offending_lines(&rel, &text));
    }
    assert!(
        found.is_empty(),
        "charts drawn or colours defined outside harness/src/plot/ (move the drawing into a plot \
         module, the colour into plot/style.rs):\n{}",
        found.join("\n")
    );
}

#[test]
fn the_grep_finds_the_drawing_code_it_replaced() {
    assert!(!offending_lines("regress/history.rs", "use plotters::prelude::*;").is_empty());
    assert!(!offending_lines(
        "papers/fragment_pt/fig8.rs",
        "let _ = plotters::style::register_font(FONT, FontStyle::Normal, f);"
    )
    .is_empty());
    assert!(!offending_lines("papers/table.rs", "let paper = RGBColor(127, 127, 127);").is_empty());
    assert!(!offending_lines(
        "plot/speed_error.rs",
        "const C: RGBColor = RGBColor(1, 2, 3);"
    )
    .is_empty());
    assert!(offending_lines("plot/history.rs", "use plotters::prelude::*;").is_empty());
    assert!(offending_lines("plot/style.rs", "RGBColor(8, 48, 107),").is_empty());
    assert!(offending_lines("regress/history.rs", "// plotters:: is for plot/").is_empty());
}
