//! The roofline's and the calibration cache's tests (calibrate/mod.rs).

use super::*;
use crate::calibrate::kernels::{additive_pipeline, calibrate_source, RASTER_LEGS, RASTER_SIZE};

fn cal() -> Calibration {
    Calibration {
        version: CALIBRATION_VERSION,
        adapter: "a".into(),
        driver: "d".into(),
        cpu_model: "c".into(),
        cpu_cores: 2,
        date_utc: String::new(),
        seconds: 1.0,
        triangles_per_sec: 1e6,
        fill_fragments_per_sec: 1e8,
        fill_format: "Rgba32Float".into(),
        compute_gflops: 10.0,
        copy_bytes_per_sec: 1e10,
        sort_keys_per_sec: 1e7,
        ray_steps_per_sec: 2e6,
        splat_fragments_per_sec: 5e7,
        gpu_sort_keys_per_sec: 4e7,
        tet_classifications_per_sec: 1e7,
        raster_seconds_per_triangle: 1.5e-6,
        raster_seconds_per_fragment: 0.8e-8,
    }
}

/// Times agree to rounding (a unit's cost is the reciprocal of its rate).
fn assert_close(got: f64, want: f64, what: &str) {
    assert!(
        (got - want).abs() <= 1e-9 * want.abs(),
        "{what}: {got} against {want}"
    );
}

fn assert_times(got: &[(Bound, f64)], want: &[(&str, f64)]) {
    let names: Vec<&str> = got.iter().map(|(b, _)| b.name()).collect();
    assert_eq!(names, want.iter().map(|(n, _)| *n).collect::<Vec<_>>());
    for ((b, g), (_, w)) in got.iter().zip(want) {
        assert_close(*g, *w, b.name());
    }
}

/// A row named after no algorithm: only its counters and its time count.
fn row(counters: &str, total_ms: f64) -> Row {
    Row {
        algorithm: "anything".into(),
        counters: counters.into(),
        total_ms: Some(total_ms),
        gpu_bytes_frame: Some(1_000_000),
        ..Row::default()
    }
}

/// Each counter is priced at its resource's rate; the bound is the slowest resource, its
/// fraction the resource's time over the frame's.
#[test]
fn the_bound_is_the_counter_whose_work_takes_longest() {
    let mut rows = vec![row(
        "triangles=40000;fragments=1000000;cpu_sort_keys=10000;ray_steps=20000;\
         splat_fragments=500000;gpu_sort_keys=40000;tet_classifications=50000;rays=7000",
        80.0,
    )];
    assert_times(
        &resource_times(&rows[0], &cal()),
        &[
            ("triangle setup", 40.0),
            ("fill", 10.0),
            // 40,000 triangles × 1 µs (setup; no covering count) + 1,000,000 fragments
            // × 8 ns.
            ("rasterisation", 48.0),
            ("splat fill", 10.0),
            ("ray steps", 10.0),
            ("cpu sort", 1.0),
            ("gpu sort", 1.0),
            ("classification", 5.0),
            ("memory", 0.1),
        ],
    );
    annotate(&mut rows, &cal());
    assert_eq!(rows[0].bound_by, Some(Bound::Rasterisation));
    assert_close(rows[0].roofline_ms.unwrap(), 48.0, "roofline_ms");
    assert_close(rows[0].limit_fraction.unwrap(), 0.6, "limit_fraction");
    assert_close(
        rows[0].normalized_time.unwrap(),
        80.0 / 48.0,
        "normalized_time",
    );
}

/// Changing one counter flips the bound: more ray steps make the row ray-step bound, more
/// splat fragments splat-fill bound, more sorted keys CPU-sort bound.
#[test]
fn changing_a_counter_flips_the_bound() {
    // Without the rasterisation figure (older calibrations), triangles and fragments are
    // priced on their own.
    let old = Calibration {
        raster_seconds_per_triangle: 0.0,
        raster_seconds_per_fragment: 0.0,
        ..cal()
    };
    for (counters, bound, ms) in [
        ("triangles=1000;ray_steps=200000", "ray steps", 100.0),
        ("triangles=150000;ray_steps=200000", "triangle setup", 150.0),
        (
            "triangles=1000;splat_fragments=10000000",
            "splat fill",
            200.0,
        ),
        (
            "triangles=1000;cpu_sort_keys=100000000",
            "cpu sort",
            10_000.0,
        ),
        (
            "triangles=1000;gpu_sort_keys=100000000",
            "gpu sort",
            2_500.0,
        ),
        ("fragments=20000000", "fill", 200.0),
        // Splat fragments early splat elimination dropped are not priced.
        (
            "triangles=1000;splat_fragments=10000000;ese_dropped_fragments=4000000",
            "splat fill",
            120.0,
        ),
        (
            "triangles=1000;tet_classifications=3000000",
            "classification",
            300.0,
        ),
    ] {
        let mut rows = vec![row(counters, 400.0)];
        annotate(&mut rows, &old);
        assert_eq!(rows[0].bound_by.map(Bound::name), Some(bound), "{counters}");
        assert_close(rows[0].roofline_ms.unwrap(), ms, counters);
        assert_close(rows[0].limit_fraction.unwrap(), ms / 400.0, counters);
    }
    // With it, triangles and fragments add up on the rasteriser, and covering tets cost
    // the fit's per-triangle figure above the setup (1.5 − 1 µs here).
    for (counters, bound, ms) in [
        // 150 ms of setup + 160 ms of fragments, against 150 and 200 alone.
        (
            "triangles=150000;fragments=20000000",
            "rasterisation",
            310.0,
        ),
        // + 100,000 covering tets × 0.5 µs.
        (
            "triangles=150000;covering_tets=100000;fragments=20000000",
            "rasterisation",
            360.0,
        ),
        // Covering faces (HAVS's triangles that yield fragments) cost the same.
        (
            "triangles=150000;covering_faces=100000;fragments=20000000",
            "rasterisation",
            360.0,
        ),
        // 150,000 triangles and 20,000 fragments: the setup (150 ms) and the fragments'
        // 0.16 ms; with all 150,000 triangles covering, 75 ms more.
        ("triangles=150000;fragments=20000", "rasterisation", 150.16),
        (
            "triangles=150000;covering_faces=150000;fragments=20000",
            "rasterisation",
            225.16,
        ),
        (
            "triangles=1000;fragments=1000;ray_steps=200000",
            "ray steps",
            100.0,
        ),
    ] {
        let mut rows = vec![row(counters, 400.0)];
        annotate(&mut rows, &cal());
        assert_eq!(rows[0].bound_by.map(Bound::name), Some(bound), "{counters}");
        assert_close(rows[0].roofline_ms.unwrap(), ms, counters);
    }
}

/// Without work counters only the memory term remains; a resource the calibration did not
/// measure (rate 0, an older calibration file) prices nothing.
#[test]
fn unknown_work_and_unmeasured_rates_are_left_out() {
    let mut rows = vec![row("rays=7000;steps_mean=24", 50.0)];
    annotate(&mut rows, &cal());
    assert_eq!(rows[0].bound_by, Some(Bound::Memory));
    let old = Calibration {
        ray_steps_per_sec: 0.0,
        ..cal()
    };
    let r = row("ray_steps=200000", 50.0);
    assert_times(&resource_times(&r, &old), &[("memory", 0.1)]);
    assert_times(
        &resource_times(&r, &cal()),
        &[("ray steps", 100.0), ("memory", 0.1)],
    );
    // A calibration from before the rasterisation benchmark prices triangles and fragments
    // on their own resources only.
    let before = Calibration {
        raster_seconds_per_triangle: 0.0,
        raster_seconds_per_fragment: 0.0,
        ..cal()
    };
    let r = row("triangles=1000;fragments=1000000", 50.0);
    assert_times(
        &resource_times(&r, &before),
        &[("triangle setup", 1.0), ("fill", 10.0), ("memory", 0.1)],
    );
}

/// A row whose fastest frame is faster than its roofline beats the bound; one exactly at
/// it, or without a bound or a time, does not.
#[test]
fn a_frame_faster_than_the_roofline_beats_it() {
    let at = |bound: Option<f64>, fastest: Option<f64>| Row {
        roofline_ms: bound,
        total_ms_min: fastest,
        ..Row::default()
    };
    assert!(beats_bound(&at(Some(10.0), Some(9.9))));
    assert!(!beats_bound(&at(Some(10.0), Some(10.0))));
    assert!(!beats_bound(&at(Some(10.0), Some(12.0))));
    assert!(!beats_bound(&at(None, Some(1.0))));
    assert!(!beats_bound(&at(Some(10.0), None)));
    // Through annotate: 1,000,000 splat fragments at 5e7/s = 20 ms against a 19 ms frame.
    let mut rows = vec![Row {
        total_ms_min: Some(19.0),
        ..row("splat_fragments=1000000", 25.0)
    }];
    annotate(&mut rows, &cal());
    assert!(beats_bound(&rows[0]));
    let faster = Calibration {
        splat_fragments_per_sec: 1e8,
        ..cal()
    };
    annotate(&mut rows, &faster);
    assert!(!beats_bound(&rows[0]));
}

/// Two measurements merge figure by figure into the faster: larger rates, smaller costs, a
/// figure one of them lacks (0) taken from the other.
#[test]
fn a_peak_keeps_the_faster_of_each_figure() {
    let a = cal();
    let b = Calibration {
        triangles_per_sec: 2e6,
        splat_fragments_per_sec: 1e7,
        tet_classifications_per_sec: 0.0,
        raster_seconds_per_triangle: 1e-6,
        raster_seconds_per_fragment: 0.0,
        date_utc: "later".into(),
        ..cal()
    };
    let p = b.peak_with(&a);
    assert_eq!(p.triangles_per_sec, 2e6);
    assert_eq!(p.splat_fragments_per_sec, 5e7);
    assert_eq!(p.tet_classifications_per_sec, 1e7);
    assert_eq!(p.raster_seconds_per_triangle, 1e-6);
    assert_eq!(p.raster_seconds_per_fragment, 0.8e-8);
    assert_eq!(p.date_utc, "later");
    assert_eq!(a.peak_with(&a), a);
}

/// The fit goes through both points; noise that tilts it below zero is clamped, never
/// priced as negative work.
#[test]
fn the_raster_fit_recovers_a_line_and_clamps_noise() {
    let line = |f: f64| 2e-7 + f * 5e-9;
    let (small, large) = (
        raster_fragments_per_triangle(4),
        raster_fragments_per_triangle(16),
    );
    assert_eq!((small, large), (10.0, 136.0));
    let (a, b) = raster_costs((small, line(small)), (large, line(large)));
    assert_close(a, 2e-7, "per triangle");
    assert_close(b, 5e-9, "per fragment");
    // Large triangles timed faster than small ones: no per-fragment cost, all per triangle.
    assert_eq!(raster_costs((10.0, 3e-7), (136.0, 2e-7)), (3e-7, 0.0));
    // A per-fragment slope steeper than the small point allows: no per-triangle cost.
    let (a, b) = raster_costs((10.0, 1e-8), (136.0, 1e-6));
    assert_eq!(a, 0.0);
    assert!(b > 0.0);
}

/// The benchmark's triangles have exactly the fragments the fit assumes: drawn once per
/// cell with fill's additive blend of 0.01, the target sums to 0.01 × the count.
#[test]
fn raster_triangles_have_the_counted_fragments() {
    let gpu = Gpu::new().expect("an adapter (lavapipe)");
    let module = gpu.shader("calibrate", &calibrate_source());
    let format = wgpu::TextureFormat::Rgba32Float;
    let pipeline = additive_pipeline(&gpu, &module, "raster test", "raster_vs", format);
    for leg in RASTER_LEGS {
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d {
                width: RASTER_SIZE,
                height: RASTER_SIZE,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        let cells = (RASTER_SIZE / leg).pow(2);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass =
                render_core::bind::color_pass(&mut enc, "raster test", &view, true, true, None);
            pass.set_pipeline(&pipeline);
            pass.draw(0..cells * 3, leg..leg + 1);
        }
        gpu.queue.submit([enc.finish()]);
        let image = gpu.read_rgba32f(&texture).unwrap();
        let sum: f64 = image.pixels.iter().map(|p| p[3] as f64).sum();
        let counted = (sum / 0.01).round();
        assert_eq!(
            counted,
            cells as f64 * raster_fragments_per_triangle(leg),
            "leg {leg}: the target sums to {sum}"
        );
    }
}

/// The roofline never looks at a row's algorithm or settings: this file quotes no
/// algorithm name of the registry (tests included), reads no row's algorithm and no
/// setting (counter names such as `ray_steps` are the only vocabulary).
#[test]
fn calibrate_names_no_algorithm() {
    for (file, source) in [
        ("mod.rs", include_str!("mod.rs")),
        ("probes.rs", include_str!("probes.rs")),
        ("kernels.rs", include_str!("kernels.rs")),
        ("control.rs", include_str!("control.rs")),
    ] {
        for name in crate::algorithms::names() {
            let quoted = format!("\"{name}\"");
            assert!(!source.contains(&quoted), "calibrate/{file} names {quoted}");
        }
        assert!(!source.contains(concat!(".algo", "rithm")), "{file}");
        assert!(!source.contains(concat!(".set", "ting")), "{file}");
    }
}

/// The control as a run measures it: every figure of `cal()` at `speed` times its rate.
fn control_at(speed: f64) -> control::Figures {
    let c = cal();
    crate::calibrate::probes::PROBES
        .iter()
        .filter(|p| p.in_control)
        .flat_map(|p| p.figures.iter())
        .map(|&f| (f, f.from_speed(f.speed(f.get(&c)) * speed)))
        .collect()
}

/// A row with a control is priced by it, not by the cached calibration: the same row and
/// counters at a control half as fast has twice the bound, and the fraction moves with it;
/// a figure the control did not measure is the calibration's times the control's factor, and
/// the row names it.
#[test]
fn a_rows_fraction_uses_its_own_rounds_control() {
    let counters = "fragments=1000000;ray_steps=20000";
    let mut rows = vec![row(counters, 80.0), row(counters, 80.0)];
    rows[0].round_control = vec![control_at(1.0); 3];
    rows[1].round_control = vec![control_at(0.5); 3];
    annotate(&mut rows, &cal());
    assert_eq!(
        rows[0].priced_with,
        control::Pricing::Control { scaled: vec![] }
    );
    assert_close(
        rows[1].roofline_ms.unwrap(),
        2.0 * rows[0].roofline_ms.unwrap(),
        "half the speed, twice the bound",
    );
    assert_close(
        rows[1].limit_fraction.unwrap(),
        2.0 * rows[0].limit_fraction.unwrap(),
        "limit_fraction",
    );
    // The fill figure missing from one round's control: the other rounds' median holds it.
    // Missing from every round: scaled from the calibration by the control's factor (0.5).
    let mut no_fill = control_at(0.5);
    no_fill.remove(&crate::results::machine::Figure::FillFragmentsPerSec);
    rows[1].round_control = vec![no_fill; 3];
    annotate(&mut rows, &cal());
    assert_eq!(
        rows[1].priced_with,
        control::Pricing::Control {
            scaled: vec![crate::results::machine::Figure::FillFragmentsPerSec]
        }
    );
    assert_close(
        rows[1].roofline_ms.unwrap(),
        2.0 * rows[0].roofline_ms.unwrap(),
        "the scaled figure",
    );
    // Without a control, the cached calibration prices the row, and says so.
    let mut plain = vec![row(counters, 80.0)];
    annotate(&mut plain, &cal());
    assert_eq!(plain[0].priced_with, control::Pricing::Calibration);
    assert_close(
        plain[0].roofline_ms.unwrap(),
        rows[0].roofline_ms.unwrap(),
        "a control at the calibration's speed",
    );
    // `priced_with` reads back what it wrote.
    for p in [&rows[1].priced_with, &plain[0].priced_with] {
        assert_eq!(&p.to_string().parse::<control::Pricing>().unwrap(), p);
    }
}

/// A row's rounds take the best of the samples around each: before and after the round
/// (several rounds), or before and after the row in file order (one variant at a time); a
/// round with no sample around it gives no control.
#[test]
fn each_round_is_bracketed_by_its_samples() {
    use control::{Control, ControlSample};
    let sample = |dataset: &str, round, rows_before, speed| ControlSample {
        dataset: dataset.into(),
        round,
        rows_before,
        at_s: 0.0,
        utc: String::new(),
        seconds: 0.1,
        figures: control_at(speed),
    };
    let fill = |f: &control::Figures| f[&crate::results::machine::Figure::FillFragmentsPerSec];
    let c = Control {
        probes: vec![],
        setup_seconds: 0.0,
        samples: vec![
            sample("a", 0, 0, 1.0),
            sample("a", 1, 0, 0.5),
            sample("a", 2, 0, 0.25),
            sample("b", 0, 0, 0.1),
        ],
    };
    let rounds = c.rounds_of("a", 2, 5);
    assert_eq!(rounds.len(), 2);
    assert_close(fill(&rounds[0]), 1e8, "round 0: the faster of 1.0 and 0.5");
    assert_close(
        fill(&rounds[1]),
        0.5e8,
        "round 1: the faster of 0.5 and 0.25",
    );
    assert_eq!(
        c.rounds_of("a", 3, 5).len(),
        3,
        "round 2: the sample before it"
    );
    assert!(
        c.rounds_of("a", 4, 5).is_empty(),
        "round 3 has no sample around it"
    );
    assert!(c.rounds_of("c", 2, 5).is_empty());

    let one_at_a_time = Control {
        probes: vec![],
        setup_seconds: 0.0,
        samples: vec![
            sample("a", 0, 0, 0.5),
            sample("a", 0, 3, 1.0),
            sample("a", 1, 6, 0.25),
        ],
    };
    assert_close(
        fill(&one_at_a_time.rounds_of("a", 1, 1)[0]),
        1e8,
        "rows 0–2",
    );
    assert_close(
        fill(&one_at_a_time.rounds_of("a", 1, 4)[0]),
        1e8,
        "rows 3–5",
    );
    assert_close(
        fill(&one_at_a_time.rounds_of("a", 1, 6)[0]),
        0.25e8,
        "row 6: only the sample before it",
    );
}
