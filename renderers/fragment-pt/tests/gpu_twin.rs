//! Pass 1 on the GPU agrees with its CPU twin (`classify::classify_tet`) on ≥ 10,000 random tets
//! seen from random directions, plus class-3 and class-4 tets built on purpose (a vertex on the
//! view ray through another vertex or through a point of an edge).

use datasets::TetMesh;
use fragment_pt::classify::{self, build_table, face_areas_f32};
use fragment_pt::{FragmentPt, FragmentPtSettings, Shading, SortMode};
use render_core::{Camera, Gpu, Optics, Projection, Renderer, TransferFunction, Viewpoint};

/// SplitMix64: a small deterministic generator for test inputs.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    fn point(&mut self, c: [f64; 3], r: f64) -> [f64; 3] {
        [0, 1, 2].map(|a| c[a] + self.range(-r, r))
    }
}

fn along(eye: [f64; 3], p: [f64; 3], k: f64) -> [f64; 3] {
    [0, 1, 2].map(|a| eye[a] + (p[a] - eye[a]) * k)
}

/// Random small tets, then class-4 tets (vertex 1 on the eye ray through vertex 0) and class-3
/// tets (vertex 0 on the eye ray through a point of edge (1, 2)).
fn build_mesh(rng: &mut Rng, camera: &Camera, random: usize, built: usize) -> TetMesh {
    let mut points: Vec<[f32; 3]> = vec![];
    let mut tets = vec![];
    let mut push = |p: [[f64; 3]; 4], points: &mut Vec<[f32; 3]>| {
        let b = points.len() as u32;
        for q in p {
            points.push(q.map(|x| x as f32));
        }
        tets.push([b, b + 1, b + 2, b + 3]);
    };
    for _ in 0..random {
        let c = rng.point([0.0; 3], 0.8);
        let p = [0; 4].map(|_| rng.point(c, 0.15));
        push(p, &mut points);
    }
    for i in 0..built {
        let c = rng.point([0.0; 3], 0.6);
        let mut p = [0; 4].map(|_| rng.point(c, 0.15));
        if i % 2 == 0 {
            p[1] = along(camera.eye, p[0], rng.range(0.9, 1.1));
        } else {
            let t = rng.range(0.2, 0.8);
            let on_edge = [0, 1, 2].map(|a| p[1][a] + (p[2][a] - p[1][a]) * t);
            p[0] = along(camera.eye, on_edge, rng.range(0.9, 1.1));
        }
        push(p, &mut points);
    }
    let scalars: Vec<f32> = (0..points.len()).map(|_| rng.unit() as f32).collect();
    TetMesh::new("random", points, scalars, "s", tets).expect("random tets")
}

#[test]
fn gpu_pass1_matches_cpu_twin() {
    let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
    let table = build_table();
    let mut rng = Rng(2006);
    let bounds = datasets::Aabb {
        min: [-1.0; 3],
        max: [1.0; 3],
    };
    let mut compared = 0usize;
    let mut near_threshold = 0usize;
    let mut per_class = [0usize; 5];
    for (round, proj) in [Projection::default(), Projection::Orthographic]
        .into_iter()
        .enumerate()
    {
        let dir = [
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        ];
        let camera = Camera::fit(
            &bounds,
            &Viewpoint::new(format!("r{round}"), dir),
            proj,
            128,
            128,
        );
        let mesh = std::sync::Arc::new(build_mesh(&mut rng, &camera, 6000, 1000));
        let tf = TransferFunction::preset("low-opacity").expect("low-opacity preset");
        let optics = Optics::for_mesh(tf, &mesh);
        let mut r = FragmentPt::new(FragmentPtSettings {
            shading: Shading::Average,
            sort: SortMode::Radix,
            slabs: None,
        });
        r.prepare(&gpu, &mesh, &optics).unwrap();
        let params = r.project_params(&camera).unwrap();
        let gpu_out = r.classify_on_gpu(&gpu, &camera).unwrap();
        assert_eq!(gpu_out.len(), mesh.num_tets());
        for (t, (g, gdepth)) in gpu_out.iter().enumerate() {
            let pos = mesh.tets[t].map(|v| mesh.points[v as usize]);
            let sc = mesh.tets[t].map(|v| mesh.scalars[v as usize]);
            let (c, cdepth) = classify::classify_tet(&params, &table, pos, sc);
            assert!(
                (gdepth - cdepth).abs() <= 1e-5 * cdepth.abs().max(1.0),
                "tet {t}: depth {gdepth} vs {cdepth}"
            );
            // Where a face area sits at the zero tolerance, f32 rounding (FMA on the GPU) may
            // decide differently: those tets are counted, not compared.
            let clip = pos.map(|p| {
                let m = params.view_proj;
                let c = [0, 1, 2, 3]
                    .map(|r| m[0][r] * p[0] + m[1][r] * p[1] + m[2][r] * p[2] + m[3][r]);
                [c[0] / c[3], c[1] / c[3]]
            });
            let (areas, eps) = face_areas_f32(clip);
            if areas
                .iter()
                .any(|a| (a.abs() - eps).abs() <= 1e-3 * eps + 1e-6 * a.abs())
            {
                near_threshold += 1;
                continue;
            }
            assert_eq!(
                g.fan,
                c.fan,
                "tet {t}: fan/class differ (gpu class {}, cpu class {})",
                g.class(),
                c.class()
            );
            per_class[c.class() as usize] += 1;
            compared += 1;
            if c.class() == 0 {
                continue;
            }
            let gn = [
                g.thick_clip[0] / g.thick_clip[3],
                g.thick_clip[1] / g.thick_clip[3],
            ];
            let cn = [
                c.thick_clip[0] / c.thick_clip[3],
                c.thick_clip[1] / c.thick_clip[3],
            ];
            assert!(
                (gn[0] - cn[0]).abs() < 1e-4 && (gn[1] - cn[1]).abs() < 1e-4,
                "tet {t}: thick {gn:?} vs {cn:?}"
            );
            assert!(
                (g.s_front - c.s_front).abs() < 2e-3,
                "tet {t}: s_f {} vs {}",
                g.s_front,
                c.s_front
            );
            assert!(
                (g.s_back - c.s_back).abs() < 2e-3,
                "tet {t}: s_b {} vs {}",
                g.s_back,
                c.s_back
            );
            let tol = 2e-3 * c.thickness.abs() + 1e-5;
            assert!(
                (g.thickness - c.thickness).abs() < tol,
                "tet {t}: l {} vs {}",
                g.thickness,
                c.thickness
            );
        }
    }
    eprintln!("compared {compared} tets (per class 0..4: {per_class:?}), {near_threshold} at the zero tolerance");
    assert!(compared >= 10_000, "only {compared} tets compared");
    // The built configurations really exercise classes 3 and 4.
    assert!(per_class[3] >= 300 && per_class[4] >= 300, "{per_class:?}");
    assert!(
        near_threshold < compared / 100,
        "{near_threshold} near the tolerance"
    );
}

/// Vertices, tets and pass-1 records split over several storage bindings (forced with 4 KiB
/// bindings) draw exactly the image of one binding each, with a CPU and the GPU sort.
#[test]
fn split_bindings_draw_the_same_image() {
    let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
    let mesh = std::sync::Arc::new(datasets::generate::from_spec("box:1k", 1).unwrap());
    let tf = TransferFunction::preset("high-opacity").unwrap();
    let optics = Optics::for_mesh(tf, &mesh);
    let vp = Viewpoint::new("oblique", [0.4, 0.6, 0.7]);
    let cam = Camera::fit(&mesh.bounds(), &vp, Projection::default(), 48, 48);
    let counter = |c: &[(String, f64)], name: &str| {
        c.iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("{name} in {c:?}"))
            .1
    };
    for sort in [SortMode::Merge, SortMode::Gpu] {
        let s = FragmentPtSettings {
            shading: Shading::Psi,
            sort,
            slabs: None,
        };
        let mut images = Vec::new();
        for r in [
            FragmentPt::new(s),
            FragmentPt::new(s).with_max_binding(4096),
        ] {
            let mut r = r;
            r.prepare(&gpu, &mesh, &optics).unwrap();
            let stats = r.render(&gpu, &cam).unwrap();
            assert!(stats.cpu_ms <= stats.total_ms, "{stats:?}");
            assert_eq!(counter(&stats.counters, "tets_behind_eye"), 0.0);
            images.push((
                r.read_image(&gpu).unwrap(),
                counter(&stats.counters, "mesh_bindings"),
            ));
        }
        assert_eq!(images[0].1, 3.0);
        assert!(images[1].1 >= 9.0, "{}", images[1].1);
        assert_eq!(images[0].0.pixels, images[1].0.pixels, "{sort:?}");
        assert!(images[0].0.pixels.iter().any(|p| p[3] > 0.1));
    }
}
