//! `tetbench publish` over the committed baselines and reproduced papers, plus one run whose
//! data set is named with markup and which kept one image, walked in headless
//! Chromium by `scripts/check-site.sh` (which installs Debian's chromium when none is on the
//! PATH): every page loads with no console error, every link and image resolves, the name
//! stays text. Then a copy of the site with one image deleted, one link broken and one live tag
//! planted must fail the same walk, each on its own count.

use std::path::{Path, PathBuf};
use std::process::Command;

use harness::report::html::HOSTILE_NAME;

const TETBENCH: &str = env!("CARGO_BIN_EXE_tetbench");

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Another run of the llvmpipe baselines' adapter, dated after every committed baseline: its
/// shell data set renamed to markup, its first row's image kept (a real PNG), the others' not.
fn hostile_run(dir: &Path) {
    let base = repo().join("reports/baselines/llvmpipe-llvm-15-0-6-256-bits-2026-12-03");
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(base.join("results.json")).unwrap()).unwrap();
    doc["machine"]["date_utc"] = "2026-12-31T00:00:00Z".into();
    for row in doc["rows"].as_array_mut().unwrap() {
        if row["dataset"] == "shell:10k" {
            row["dataset"] = HOSTILE_NAME.into();
        }
    }
    doc["rows"][0]["image"] = "images/kept.png".into();
    std::fs::create_dir_all(dir.join("images")).unwrap();
    std::fs::copy(
        repo().join("reports/reproduced/havs/charts/table1_ms.png"),
        dir.join("images/kept.png"),
    )
    .unwrap();
    std::fs::write(
        dir.join("results.json"),
        serde_json::to_string(&doc).unwrap(),
    )
    .unwrap();
}

struct Walk {
    ok: bool,
    summary: serde_json::Value,
    log: String,
}

fn walk(site: &Path) -> Walk {
    let json = site.with_extension("check.json");
    let o = Command::new("timeout")
        .arg("600")
        .arg("bash")
        .arg(repo().join("scripts/check-site.sh"))
        .arg(site)
        .args(["--expect-text", HOSTILE_NAME, "--json"])
        .arg(&json)
        .output()
        .unwrap();
    let log = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let summary = std::fs::read_to_string(&json)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_else(|| panic!("the browser walk wrote no summary:\n{log}"));
    Walk {
        ok: o.status.success(),
        summary,
        log,
    }
}

fn count(w: &Walk, key: &str) -> usize {
    w.summary[key].as_array().map_or(usize::MAX, |a| a.len())
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.path().is_dir() {
            copy_tree(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

#[test]
fn the_published_site_passes_a_real_browser_and_a_broken_one_does_not() {
    let tmp = Path::new(env!("CARGO_TARGET_TMPDIR")).join("publish-site");
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let hostile = tmp.join("hostile-run");
    hostile_run(&hostile);
    let site = tmp.join("site");
    let mut args: Vec<PathBuf> = std::fs::read_dir(repo().join("reports/baselines"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    args.sort();
    args.push(repo().join("reports/reproduced"));
    args.push(hostile.clone());
    let o = Command::new(TETBENCH)
        .arg("publish")
        .args(&args)
        .arg("--out")
        .arg(&site)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "publish failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );

    // What the site holds: every run's report, the llvmpipe history (the baselines and the
    // hostile run), both sets of reproduced papers, the charts across adapters, the one kept image.
    for page in [
        "index.html",
        "runs/llvmpipe-llvm-15-0-6-256-bits-2026-12-01/index.html",
        "runs/nvidia-h200-2026-12-04/index.html",
        "runs/hostile-run/index.html",
        "runs/hostile-run/images/kept.png",
        "papers/reproduced/havs/report.html",
        "papers/nvidia-h200-2026-12-04/gator/report.html",
    ] {
        assert!(site.join(page).is_file(), "the site lacks {page}");
    }
    // Every page below the front page links back to it, however deep it lies.
    for (page, up) in [
        ("runs/hostile-run/index.html", "../../"),
        ("papers/reproduced/havs/report.html", "../../../"),
    ] {
        let html = std::fs::read_to_string(site.join(page)).unwrap();
        let back = format!("<a href=\"{up}index.html\">");
        assert!(
            html.contains(&back),
            "{page} has no link {back} to the front page"
        );
    }
    let front = std::fs::read_to_string(site.join("index.html")).unwrap();
    harness::report::html::assert_no_live_markup(&front);
    assert!(
        !front.contains("all results</a></nav>"),
        "the front page links to itself"
    );
    assert!(
        front.contains("group(s) with a step"),
        "no history on the front page"
    );
    assert!(front.contains("charts/across_adapters_"));
    // The cross-adapter charts name their scale: how many rows each pricing gave.
    assert!(
        front.contains("priced by the control their run measured beside them")
            && front.contains("by their adapter&#x27;s cached calibration"),
        "the charts do not say which scale they use"
    );
    // A baseline keeps no images: its report says so and links none.
    let baseline =
        std::fs::read_to_string(site.join("runs/nvidia-h200-2026-12-04/index.html")).unwrap();
    assert!(baseline.contains("images-absent"));
    assert!(!baseline.contains("src=\"images/"));
    // A second publish replaces the site; another directory is never replaced.
    let again = Command::new(TETBENCH)
        .arg("publish")
        .arg(&hostile)
        .arg("--out")
        .arg(&site)
        .output()
        .unwrap();
    assert!(again.status.success());
    let o = Command::new(TETBENCH)
        .arg("publish")
        .arg(&hostile)
        .arg("--out")
        .arg(&hostile)
        .output()
        .unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("not empty"));
    let o = Command::new(TETBENCH)
        .arg("publish")
        .args(&args)
        .arg("--out")
        .arg(&site)
        .output()
        .unwrap();
    assert!(o.status.success());

    let good = walk(&site);
    assert!(good.ok, "the site fails the browser walk:\n{}", good.log);
    for key in [
        "console_errors",
        "missing_images",
        "broken_links",
        "external",
        "live_markup",
        "unreachable_pages",
        "missing_text",
    ] {
        assert_eq!(count(&good, key), 0, "{key}:\n{}", good.log);
    }
    let pages = good.summary["pages"].as_u64().unwrap();
    assert!(pages >= 16, "only {pages} pages walked:\n{}", good.log);
    println!(
        "site walked: {pages} pages, {} links, {} images",
        good.summary["links"], good.summary["images"]
    );

    // The same walk over a broken copy must fail, on each count it is meant to see.
    let broken = tmp.join("broken-site");
    copy_tree(&site, &broken);
    std::fs::remove_file(broken.join("runs/hostile-run/images/kept.png")).unwrap();
    let index = broken.join("index.html");
    let mut text = std::fs::read_to_string(&index).unwrap();
    text = text.replace(
        "runs/hostile-run/index.html",
        "runs/hostile-run/nowhere.html",
    );
    text.push_str(HOSTILE_NAME);
    std::fs::write(&index, text).unwrap();
    let bad = walk(&broken);
    assert!(!bad.ok, "the broken site passed:\n{}", bad.log);
    assert!(count(&bad, "missing_images") >= 1, "{}", bad.log);
    assert!(count(&bad, "broken_links") >= 1, "{}", bad.log);
    assert!(count(&bad, "live_markup") >= 1, "{}", bad.log);
    assert!(count(&bad, "console_errors") >= 1, "{}", bad.log);
}
