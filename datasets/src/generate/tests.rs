//! The generators' specs, sizes, fields and lattices.

use super::*;

#[test]
fn blob_lattice_agrees_with_the_field_at_every_point() {
    let field = FieldEval::new(Field::Blobs, 11);
    let (dims, origin, h) = ([7, 5, 9], [-1.0, -0.8, -1.2], [0.3, 0.4, 0.27]);
    let lattice = field.on_lattice(dims, origin, h).unwrap();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let p = std::array::from_fn(|a| origin[a] + [i, j, k][a] as f64 * h[a]);
                let (want, got) = (field.eval(p), lattice.at([i, j, k]));
                assert!(
                    (want - got).abs() <= 1e-12 * want.max(1e-300),
                    "{want} {got}"
                );
            }
        }
    }
    assert!(FieldEval::new(Field::Radial, 11)
        .on_lattice(dims, origin, h)
        .is_none());
}

#[test]
fn sizes_and_specs_parse() {
    assert_eq!(parse_size("200k"), Some(200_000));
    assert_eq!(parse_size("1M"), Some(1_000_000));
    assert_eq!(parse_size("1.5m"), Some(1_500_000));
    assert_eq!(parse_size("5000"), Some(5000));
    assert_eq!(parse_size("0"), None);
    assert_eq!(parse_size("lots"), None);
    let s = parse_spec("box:200k:field=blobs:seed=3").unwrap();
    assert_eq!(
        (s.kind, s.target_tets, s.field, s.seed),
        (Kind::Box, 200_000, Field::Blobs, Some(3))
    );
    assert!(matches!(
        parse_spec("cube:1k"),
        Err(ErrorKind::Syntax { .. })
    ));
    assert!(matches!(
        parse_spec("box:1k:field=nope"),
        Err(ErrorKind::Syntax { .. })
    ));
    assert!(matches!(parse_spec("box:"), Err(ErrorKind::Syntax { .. })));
    assert!(is_spec("shell:1m") && !is_spec("spx") && !is_spec("C:/data/x.vtk"));
}

#[test]
fn box_cells_hit_targets() {
    for t in [1_000, 5_000, 50_000, 200_000, 1_000_000, 20_000_000] {
        let c = box_cells(t);
        let n = 5 * c.iter().product::<usize>();
        assert!(
            ((n as f64) - t as f64).abs() / (t as f64) < 0.03,
            "{t}: {c:?} gives {n}"
        );
    }
    // Shape first, then count: within 25 % below 10 k tets, 10 % below 100 k, else 5 %.
    for (t, tolerance) in [
        (1_000, 0.25),
        (10_000, 0.10),
        (1_000_000, 0.05),
        (20_000_000, 0.05),
    ] {
        let (n, m) = shell_cells(t);
        let got = 36 * n * n * m;
        assert!(
            ((got as f64) - t as f64).abs() / (t as f64) < tolerance,
            "{t}: ({n},{m}) gives {got}"
        );
    }
}

#[test]
fn marschner_lobb_range() {
    let f = FieldEval::new(Field::MarschnerLobb, 0);
    // ρ(0,0,-1) = (1 + 1 + α·2)/(2(1+α)) = 1; ρ at the top centre: (0 + α(1+cos 0))/(2.5) = 0.2
    assert!((f.eval([0.0, 0.0, -1.0]) - 1.0).abs() < 1e-12);
    assert!((f.eval([0.0, 0.0, 1.0]) - 0.2).abs() < 1e-12);
}
