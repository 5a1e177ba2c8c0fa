use super::*;
use crate::results::{FrameSamples, RunDescription};

#[test]
fn schedule_alternates_which_side_goes_first() {
    use Side::{Base as A, New as B};
    let got: Vec<Side> = schedule(4).into_iter().map(|(_, s)| s).collect();
    assert_eq!(got, [A, B, B, A, A, B, B, A]);
    let pairs: Vec<u32> = schedule(3).into_iter().map(|(p, _)| p).collect();
    assert_eq!(pairs, [0, 0, 1, 1, 2, 2]);
}

fn row(alg: &str, vp: &str, frames: &[f64]) -> Row {
    Row {
        algorithm: alg.into(),
        settings: "k=2".parse().unwrap(),
        dataset: "box:1k".into(),
        viewpoint: vp.into(),
        tets: 1000,
        frames: frames.len() as u32,
        image_f32: format!("images/{alg}{vp}.f32.zz"),
        image_hash: "h".into(),
        samples: FrameSamples {
            total_ms: frames.to_vec(),
            cpu_ms: frames.iter().map(|f| f / 2.0).collect(),
            gpu_ms: vec![],
            ..Default::default()
        },
        total_ms: Some(frames[0]),
        ..Default::default()
    }
}

fn round(dir: &Path, rows: Vec<Row>) -> ResultsFile {
    let file = ResultsFile {
        control: None,
        schema_version: crate::results::SCHEMA_VERSION,
        machine: crate::results::machine::MachineInfo::collect(),
        run: RunDescription {
            rounds: 1,
            frames: 2,
            ..Default::default()
        },
        finished_utc: None,
        rows,
        errors: vec![],
    };
    std::fs::create_dir_all(dir).unwrap();
    crate::results::write_json(dir, &file).unwrap();
    file
}

/// Three rounds of two frames become one results set of 3 rounds: each row's samples are the
/// rounds' frames in turn (so compare's round values are the rounds' medians), the summary
/// columns those of all six frames, and image paths point into the first round.
#[test]
fn rounds_merge_into_one_run_of_n_rounds() {
    let tmp = tempfile::tempdir().unwrap();
    let side = tmp.path().join("base");
    let dirs: Vec<PathBuf> = (1..=3).map(|i| side.join(format!("round-0{i}"))).collect();
    for (i, d) in dirs.iter().enumerate() {
        let t = 10.0 * (i + 1) as f64;
        // Each round's roofline columns are of its own median.
        let mut havs = row("havs", "+x", &[t, t + 1.0]);
        havs.roofline_ms = Some(10.25);
        crate::calibrate::set_fraction(&mut havs);
        round(d, vec![havs, row("gator-pt", "+x", &[1.0, 3.0])]);
    }
    let merged = merge_rounds(&dirs, &side).unwrap();
    assert_eq!(merged.run.rounds, 3);
    assert_eq!(merged.run.merged_from.len(), 3);
    let havs = &merged.rows[0];
    assert_eq!(havs.samples.total_ms, [10.0, 11.0, 20.0, 21.0, 30.0, 31.0]);
    assert_eq!(havs.samples.cpu_ms.len(), 6);
    assert_eq!(havs.frames, 6);
    assert_eq!(havs.total_ms, Some(20.5));
    assert_eq!(
        (havs.total_ms_min, havs.total_ms_max),
        (Some(10.0), Some(31.0))
    );
    assert_eq!(havs.image_f32, "round-01/images/havs+x.f32.zz");
    // The limit fraction is of the merged median, not the first round's (0.5, not 1).
    assert_eq!(havs.limit_fraction, Some(0.5));
    assert_eq!(havs.normalized_time, Some(2.0));
    let values = crate::regress::compare::round_values(havs, "total_ms", 3, false).unwrap();
    assert_eq!(values, [10.5, 20.5, 30.5]);
    assert!(merged.errors.is_empty(), "{:?}", merged.errors);
}

/// A row that fails in one round keeps the others' samples and says which round failed (so
/// compare sees a failing row); an image that differs between rounds is noted.
#[test]
fn a_failed_round_is_named_and_a_changed_image_noted() {
    let tmp = tempfile::tempdir().unwrap();
    let side = tmp.path().join("new");
    let dirs: Vec<PathBuf> = (1..=3).map(|i| side.join(format!("round-0{i}"))).collect();
    let mut failed = row("havs", "+x", &[1.0, 1.0]);
    failed.error = Some(crate::results::Failure::new(
        crate::results::Stage::Render,
        "out of memory",
    ));
    failed.samples = FrameSamples::default();
    let mut other_image = row("havs", "+x", &[3.0, 3.0]);
    other_image.image_hash = "other".into();
    round(&dirs[0], vec![failed]);
    round(&dirs[1], vec![row("havs", "+x", &[2.0, 2.0])]);
    round(&dirs[2], vec![other_image]);
    let merged = merge_rounds(&dirs, &side).unwrap();
    let r = &merged.rows[0];
    assert_eq!(r.error_text(), "round 1: out of memory");
    assert_eq!(r.samples.total_ms, [2.0, 2.0, 3.0, 3.0]);
    assert_eq!(r.image_f32, "round-02/images/havs+x.f32.zz");
    assert_eq!(merged.errors.len(), 1, "{:?}", merged.errors);
    assert!(merged.errors[0].contains("image differs between rounds"));
    // All rounds fine and equal: nothing to say.
    for d in &dirs {
        round(d, vec![row("havs", "+x", &[2.0, 2.0])]);
    }
    let merged = merge_rounds(&dirs, &side).unwrap();
    assert!(merged.rows[0].ok() && merged.errors.is_empty());
}

/// Rounds of different frame counts are not one side's rounds.
#[test]
fn rounds_of_different_frames_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let dirs: Vec<PathBuf> = (1..=2).map(|i| tmp.path().join(format!("r{i}"))).collect();
    round(&dirs[0], vec![row("havs", "+x", &[1.0, 1.0])]);
    let mut f = round(&dirs[1], vec![row("havs", "+x", &[1.0, 1.0])]);
    f.run.frames = 5;
    crate::results::write_json(&dirs[1], &f).unwrap();
    let e = merge_rounds(&dirs, tmp.path()).unwrap_err().to_string();
    assert!(e.contains("r2") && e.contains("frames"), "{e}");
}

/// The drift of a pair is NEW/BASE over matched rows; each side is also measured against its
/// own first round.
#[test]
fn pair_drift_is_the_median_row_ratio() {
    let tmp = tempfile::tempdir().unwrap();
    let mk = |name: &str, scale: f64| {
        round(
            &tmp.path().join(name),
            vec![
                row("a", "+x", &[10.0 * scale, 10.0 * scale]),
                row("b", "+x", &[20.0 * scale, 20.0 * scale]),
                row("c", "+x", &[5.0 * scale * 2.0, 5.0 * scale * 2.0]),
            ],
        )
    };
    let base = vec![mk("b1", 1.0), mk("b2", 1.5)];
    let new = vec![mk("n1", 1.1), mk("n2", 1.5)];
    let d = pair_drift(&base, &new);
    assert_eq!(d.len(), 2);
    assert_eq!(d[0].order, "BASE, NEW");
    assert_eq!(d[1].order, "NEW, BASE");
    assert_eq!(d[0].rows, 3);
    assert!((d[0].ratio.unwrap() - 1.1).abs() < 1e-12);
    assert!((d[1].ratio.unwrap() - 1.0).abs() < 1e-12);
    assert!((d[1].base_vs_first_round.unwrap() - 1.5).abs() < 1e-12);
    assert!((d[1].new_vs_first_round.unwrap() - 1.5 / 1.1).abs() < 1e-12);
    assert!(drift_text(&d).contains("pair  2 (NEW, BASE): NEW/BASE ×1.000 over 3 rows"));
}
