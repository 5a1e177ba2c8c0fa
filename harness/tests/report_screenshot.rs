//! The HTML report as a user sees it: written for synthetic rows of every algorithm's default
//! variants (no GPU needed), then screenshotted in headless Chromium with
//! `scripts/screenshot-report.sh`. Skips with a printed reason when no Chromium is installed
//! (the test never installs it). The report and `report-screenshot.png` stay in
//! `target/tmp/report-screenshot/` to be looked at.

use std::path::Path;
use std::process::Command;

use harness::plot::style::StyleBook;
use harness::results::machine::MachineInfo;
use harness::results::{ResultsFile, Row, RunDescription, SCHEMA_VERSION};

fn row(algorithm: &str, settings: &str, dataset: &str, viewpoint: &str, i: usize) -> Row {
    let speed = 1e5 * (1.0 + i as f64) * if dataset == "box:10k" { 1.0 } else { 0.7 };
    let psnr = if algorithm == "havs" && dataset == "shell:10k" {
        14.0
    } else {
        40.0 + i as f64
    };
    Row {
        algorithm: algorithm.into(),
        settings: settings.parse().unwrap(),
        dataset: dataset.into(),
        tets: 10_000,
        viewpoint: viewpoint.into(),
        width: 128,
        height: 128,
        total_ms: Some(1e7 / speed),
        cpu_ms: None,
        gpu_ms: None,
        fps: None,
        control_factor: None,
        priced_with: Default::default(),
        round_control: vec![],
        tets_per_sec: Some(speed * if viewpoint == "+x" { 1.1 } else { 1.0 }),
        gpu_bytes: Some(1_000_000),
        bytes_per_tet: Some(100.0),
        rmse: None,
        psnr_db: Some(psnr + if viewpoint == "+x" { 1.0 } else { 0.0 }),
        max_abs_error: None,
        bad_pixel_share: None,
        adapter: "synthetic".into(),
        backend: "none".into(),
        total_ms_min: None,
        total_ms_max: None,
        cpu_ms_min: None,
        cpu_ms_max: None,
        gpu_ms_min: None,
        gpu_ms_max: None,
        frames: 1,
        warmup: 0,
        gpu_bytes_persistent: None,
        gpu_bytes_frame: None,
        stages: Default::default(),
        counters: Default::default(),
        covered_pixels: None,
        transfer_function: "low-opacity".into(),
        projection: "perspective30".into(),
        device_type: String::new(),
        driver: String::new(),
        image: String::new(),
        reference_image: String::new(),
        heatmap: String::new(),
        image_f32: String::new(),
        image_hash: String::new(),
        roofline_ms: None,
        limit_fraction: None,
        bound_by: None,
        normalized_time: None,
        host_peak_bytes: None,
        harness_ms: None,
        suspect: None,
        error: None,
        tile_counts: String::new(),
        samples: Default::default(),
    }
}

fn synthetic_run() -> ResultsFile {
    let mut rows = vec![];
    for dataset in ["box:10k", "shell:10k"] {
        let mut i = 0;
        // The default run: every algorithm, no peers (they come only with --peers).
        for name in harness::algorithms::names()
            .into_iter()
            .filter(|n| !harness::algorithms::is_peer(n))
        {
            for r in harness::algorithms::variants(name).unwrap() {
                let settings = r.settings().to_string();
                for vp in ["+x", "+x+y+z", "-x+y-z"] {
                    rows.push(row(name, &settings, dataset, vp, i));
                }
                i += 1;
            }
        }
    }
    ResultsFile {
        control: None,
        schema_version: SCHEMA_VERSION,
        machine: MachineInfo::collect(),
        run: RunDescription {
            reference: true,
            ..Default::default()
        },
        finished_utc: None,
        rows,
        errors: vec![],
    }
}

fn chromium() -> Option<String> {
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .find(|b| {
            Command::new("sh")
                .args(["-c", &format!("command -v {b}")])
                .output()
                .map(|o| o.status.success())
                .unwrap_or(false)
        })
        .map(|b| b.to_string())
}

#[test]
fn report_screenshot_in_headless_chromium() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("report-screenshot");
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&out).unwrap();
    let file = synthetic_run();
    harness::report::write(&out, &file).unwrap();
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    // Speed vs error comes first, one chart per data set.
    let first = html.find("<img").unwrap();
    // (split per algorithm when one legend would hold more than 18 variants)
    assert!(html[first..].starts_with("<img src=\"charts/speed_error_box_10k"));
    assert!(html.contains("charts/speed_error_shell_10k"));
    // HAVS at 14 dB on the shell is suspect, and marked.
    assert!(html.contains("class=\"suspect\""));

    let Some(browser) = chromium() else {
        println!("SKIPPED: no Chromium (chromium, chromium-browser, google-chrome) on PATH; install Debian's chromium to take the screenshot");
        return;
    };
    let png = out.join("report-screenshot.png");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/screenshot-report.sh");
    let status = Command::new("timeout")
        .arg("180")
        .arg("bash")
        .arg(&script)
        .arg(&out)
        .arg(&png)
        .env("WINDOW_SIZE", "1400,1400")
        .status()
        .unwrap();
    assert!(status.success(), "{browser} screenshot failed: {status}");
    let shot = image::open(&png).unwrap().to_rgb8();
    assert_eq!(shot.dimensions(), (1400, 1400));
    // The first chart is on screen: the markers' exact colours appear in the screenshot (the
    // chart is shown at its own size, so marker interiors are not resampled).
    let points: Vec<(&str, String)> = file
        .rows
        .iter()
        .map(|r| (r.algorithm.as_str(), r.settings.to_string()))
        .collect();
    let book = StyleBook::new(points.iter().map(|(a, s)| (*a, s.as_str())));
    for name in harness::algorithms::names()
        .into_iter()
        .filter(|n| !harness::algorithms::is_peer(n))
    {
        let colours: Vec<[u8; 3]> = book
            .iter()
            .filter(|((a, _), _)| a == name)
            .map(|(_, s)| [s.color.0, s.color.1, s.color.2])
            .collect();
        let hits = shot.pixels().filter(|p| colours.contains(&p.0)).count();
        assert!(
            hits > 50,
            "{name}'s colours are not in the screenshot ({hits} pixels)"
        );
    }
    println!("report screenshot: {}", png.display());
}
