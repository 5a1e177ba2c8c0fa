//! The current figures of the manual are the tool's output on committed results, never typed
//! by hand: a page holds each such table between two comments,
//!
//! ```text
//! <!-- tetbench analyze SUBCOMMAND ARGS… -->
//! …the command's Markdown, as it wrote it…
//! <!-- end of tetbench's output -->
//! ```
//!
//! and this test runs every such command from the repository's root with `--out FILE` and
//! fails where the page's text differs from what the command writes now (code or inputs
//! changed). `TETBENCH_BLESS=1 cargo test -p harness --test docs_tables` writes the output into
//! the pages. Only `analyze` commands may be named: they read committed files and measure
//! nothing.

use std::path::{Path, PathBuf};
use std::process::Command;

const OPEN: &str = "<!-- tetbench analyze ";
const CLOSE: &str = "<!-- end of tetbench's output -->";

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A generated block: the command's arguments after `tetbench`, and the byte range of the
/// text between the two comments.
struct Generated {
    args: Vec<String>,
    body: std::ops::Range<usize>,
    line: usize,
}

fn generated_blocks(page: &Path, text: &str) -> Vec<Generated> {
    let mut out = vec![];
    let mut from = 0;
    while let Some(at) = text[from..].find(OPEN).map(|i| i + from) {
        // Only a comment that opens its line: a page may name the syntax in its prose.
        if at > 0 && !text[..at].ends_with('\n') {
            from = at + OPEN.len();
            continue;
        }
        let line = text[..at].lines().count() + 1;
        let end_of_comment = text[at..]
            .find("-->")
            .map(|i| at + i)
            .unwrap_or_else(|| panic!("{}:{line}: the comment is not closed", page.display()));
        let command = &text[at + "<!-- tetbench ".len()..end_of_comment];
        let body_start = text[end_of_comment..]
            .find('\n')
            .map(|i| end_of_comment + i + 1)
            .unwrap_or_else(|| panic!("{}:{line}: nothing after the comment", page.display()));
        let body_end = text[body_start..]
            .find(CLOSE)
            .map(|i| body_start + i)
            .unwrap_or_else(|| panic!("{}:{line}: no `{CLOSE}` after it", page.display()));
        out.push(Generated {
            args: command.split_whitespace().map(str::to_string).collect(),
            body: body_start..body_end,
            line,
        });
        from = body_end + CLOSE.len();
    }
    out
}

/// What the command writes now.
fn output_of(page: &Path, block: &Generated, scratch: &Path) -> String {
    let out = scratch.join(format!("block-{}.md", block.line));
    let status = Command::new(env!("CARGO_BIN_EXE_tetbench"))
        .args(&block.args)
        .arg("--out")
        .arg(&out)
        .current_dir(root())
        .stdout(std::process::Stdio::null())
        .status()
        .expect("cannot start tetbench");
    assert!(
        status.success(),
        "{}:{}: `tetbench {}` failed ({status})",
        page.display(),
        block.line,
        block.args.join(" ")
    );
    let text = std::fs::read_to_string(&out).unwrap();
    format!("{}\n", text.trim_matches('\n'))
}

fn pages() -> Vec<PathBuf> {
    let mut pages: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    pages
}

#[test]
fn the_manuals_tables_are_the_tools_output_on_committed_results() {
    let bless = std::env::var_os("TETBENCH_BLESS").is_some();
    let scratch = tempfile::tempdir().unwrap();
    let mut stale = vec![];
    let mut blocks = 0;
    for page in pages() {
        let mut text = std::fs::read_to_string(&page).unwrap();
        let found = generated_blocks(&page, &text);
        blocks += found.len();
        // Back to front, so that rewriting a block keeps the earlier ranges valid.
        for block in found.iter().rev() {
            let now = output_of(&page, block, scratch.path());
            if text[block.body.clone()] != now {
                stale.push(format!("{}:{}", page.display(), block.line));
                text.replace_range(block.body.clone(), &now);
            }
        }
        if bless {
            std::fs::write(&page, &text).unwrap();
        }
    }
    assert!(
        blocks >= 2,
        "the manual's generated tables are gone ({blocks} found)"
    );
    assert!(
        bless || stale.is_empty(),
        "these tables differ from what the tool writes now: {}\n\
         regenerate them with TETBENCH_BLESS=1 cargo test -p harness --test docs_tables",
        stale.join(", ")
    );
}

#[test]
fn blocks_are_found_between_the_two_comments() {
    let page = Path::new("page.md");
    let text =
        "x\n<!-- tetbench analyze medians a=b -->\n| 1 |\n<!-- end of tetbench's output -->\ny\n";
    let found = generated_blocks(page, text);
    assert_eq!(found.len(), 1);
    assert_eq!(found[0].args, ["analyze", "medians", "a=b"]);
    assert_eq!(&text[found[0].body.clone()], "| 1 |\n");
    assert_eq!(found[0].line, 2);
    let prose = "between `<!-- tetbench analyze … -->` and its end\n";
    assert!(generated_blocks(page, prose).is_empty());
}
