//! The harness driven in-process through its command line and run loop: a row that fails (an
//! error, even a panic inside a renderer) is recorded and the run goes on; the settings filter
//! picks variants. The binary itself is tested in harness/tests/cli.rs.

use clap::Parser;
use datasets::TetMesh;
use harness::cli::{Cli, Command};
use harness::results::ResultsFile;
use render_core::{Camera, FrameStats, Gpu, Image, Optics, Prepared, Renderer};

/// Wraps a real renderer and fails on purpose at chosen viewpoints: the stand-in for an
/// out-of-memory or device error in the middle of a run.
struct FailsAt {
    inner: Box<dyn Renderer>,
    error_at: &'static str,
    panic_at: &'static str,
}

impl Renderer for FailsAt {
    fn algorithm(&self) -> &'static str {
        self.inner.algorithm()
    }
    fn settings(&self) -> render_core::Settings {
        self.inner.settings()
    }
    fn prepare(
        &mut self,
        gpu: &Gpu,
        mesh: &std::sync::Arc<TetMesh>,
        optics: &Optics,
    ) -> anyhow::Result<Prepared> {
        self.inner.prepare(gpu, mesh, optics)
    }
    fn render(&mut self, gpu: &Gpu, camera: &Camera) -> anyhow::Result<FrameStats> {
        if camera.viewpoint == self.error_at {
            anyhow::bail!("simulated out of memory");
        }
        if camera.viewpoint == self.panic_at {
            panic!("simulated device loss");
        }
        self.inner.render(gpu, camera)
    }
    fn read_image(&mut self, gpu: &Gpu) -> anyhow::Result<Image> {
        self.inner.read_image(gpu)
    }
}

fn config(args: &[&str]) -> harness::run::RunConfig {
    let cli = Cli::try_parse_from(args).unwrap();
    let Command::Run(run) = cli.command else {
        panic!("not a run")
    };
    run.to_config(cli.data_dir, args.iter().map(|s| s.to_string()).collect())
        .unwrap()
}

#[test]
fn failing_rows_are_recorded_and_the_run_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let cache = dir.path().join("cache");
    let cfg = config(&[
        "tetbench",
        "run",
        "--algorithms",
        "gator-pt",
        "--datasets",
        "box:2k",
        "--viewpoints",
        "axes",
        "--resolution",
        "24",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--settings",
        "variant=constant",
        "--out",
        out.to_str().unwrap(),
        "--cache-dir",
        cache.to_str().unwrap(),
    ]);
    let factory = |name: &str| -> anyhow::Result<Vec<Box<dyn Renderer>>> {
        Ok(harness::algorithms::variants(name)?
            .into_iter()
            .map(|inner| {
                Box::new(FailsAt {
                    inner,
                    error_at: "-x",
                    panic_at: "+y",
                }) as Box<dyn Renderer>
            })
            .collect())
    };
    let outcome = harness::run::run(&cfg, &factory).unwrap();
    assert_eq!(outcome.rows, 6);
    assert_eq!(outcome.failed_rows, 2);
    assert!(!outcome.all_ok());

    let json = ResultsFile::read(&out).unwrap();
    assert_eq!(json.rows.len(), 6);
    for r in &json.rows {
        assert!(r.settings.is("variant", "constant"), "{}", r.settings);
        match r.viewpoint.as_str() {
            "-x" => assert!(
                r.error_text().contains("simulated out of memory") && r.total_ms.is_none(),
                "{r:?}"
            ),
            "+y" => assert!(
                r.error_text().contains("panicked")
                    && r.error_text().contains("simulated device loss"),
                "{r:?}"
            ),
            _ => {
                assert!(r.ok(), "{r:?}");
                assert!(r.tets_per_sec.unwrap() > 0.0 && r.psnr_db.unwrap().is_finite());
            }
        }
    }
    // The report lists the failures too.
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("simulated out of memory") && html.contains("simulated device loss"));
}

#[test]
fn settings_filter_selects_variants() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let cfg = config(&[
        "tetbench",
        "run",
        "--algorithms",
        "gator-pt",
        "--datasets",
        "box:1k",
        "--viewpoints",
        "+z",
        "--resolution",
        "16",
        "--frames",
        "1",
        "--settings",
        "variant=linear",
        "--no-reference",
        "--no-report",
        "--out",
        out.to_str().unwrap(),
    ]);
    let outcome = harness::run::run(&cfg, &harness::algorithms::variants).unwrap();
    assert!(outcome.all_ok());
    let json = ResultsFile::read(&out).unwrap();
    assert_eq!(json.rows.len(), 1);
    assert!(json.rows[0].settings.is("variant", "linear"));
    assert_eq!(
        json.rows[0].psnr_db, None,
        "--no-reference leaves the error metrics empty"
    );
    assert!(!out.join("index.html").exists());
}
