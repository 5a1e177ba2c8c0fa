//! GPU tests of the GATOR renderer on the headless device (lavapipe on CI):
//! the vertex shader's classification against its CPU twin on 100k+ random tets, exact images
//! where the method is exact (constant field, orthographic axis views full of degenerate
//! projections), and chunked storage bindings drawing the same image as one binding; the
//! device-side sort (`sort=gpu-radix`): its order is a back-to-front permutation, and chunked
//! tets draw the image of one binding.

use datasets::TetMesh;
use gator_pt::{classify_gpu, classify_tet, CellModel, GatorPt, GatorSort, VisibilityOrder};
use glam::DVec3;
use render_core::transfer::{ColorPoint, KappaPoint};
use render_core::{Camera, Gpu, Image, Optics, Projection, Renderer, TransferFunction, Viewpoint};

fn gpu() -> Gpu {
    std::env::set_var(
        "XDG_RUNTIME_DIR",
        std::env::var("XDG_RUNTIME_DIR").unwrap_or_else(|_| "/tmp".into()),
    );
    Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)")
}

/// xorshift64*: deterministic, no dependency.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    fn unit(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length();
            if l > 0.05 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

/// Case of the CPU twin, or `None` when moving a projected point by 1e-5 of the tet's screen
/// size can change it (a tie at f32 precision: GPU and CPU may legitimately
/// disagree there, and the geometry is continuous across the tie).
fn robust_case(proj: [[f64; 3]; 4]) -> Option<u8> {
    let c = gator_pt::classify_cpu(proj).case;
    let mut size: f64 = 0.0;
    for p in &proj {
        for q in &proj {
            size = size.max((p[0] - q[0]).hypot(p[1] - q[1]));
        }
    }
    // Each vertex moved by ±δ along x and along y: a vertex lying on a line through two
    // others (the ties of tests 1-4) crosses it in one of these directions.
    let d = 1e-5 * size;
    for i in 0..4 {
        for (dx, dy) in [(d, 0.0), (-d, 0.0), (0.0, d), (0.0, -d)] {
            let mut p = proj;
            p[i][0] += dx;
            p[i][1] += dy;
            if gator_pt::classify_cpu(p).case != c {
                return None;
            }
        }
    }
    Some(c)
}

/// The vertex shader's classification (case of Table 1, thick vertex, thickness, scalars at
/// the ends) agrees with the f64 CPU twin on 102,400 random tets seen from 200 random
/// directions (perspective and orthographic), plus tets made degenerate on purpose.
#[test]
fn gpu_classification_matches_cpu_twin() {
    let gpu = gpu();
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let batches = 200;
    let per_batch = 512;
    let (mut total, mut robust, mut case_agree, mut robust_agree) =
        (0usize, 0usize, 0usize, 0usize);
    let mut robust_generic = 0usize;
    let mut flat = 0usize;
    let mut err_generic = [0.0f64; 3];
    let mut err_degenerate = [0.0f64; 3];
    let mut degenerate = 0usize;
    let mut hist = [0usize; 15];
    for batch in 0..batches {
        let dir = rng.unit();
        let proj = if batch % 4 == 3 {
            Projection::Orthographic
        } else {
            Projection::default()
        };
        let bounds = datasets::Aabb {
            min: [-1.6; 3],
            max: [1.6; 3],
        };
        let cam = Camera::fit(
            &bounds,
            &Viewpoint::new("random", dir.into()),
            proj,
            512,
            512,
        );
        let eye = DVec3::from(cam.eye);
        let fwd = DVec3::from(cam.forward());
        let mut points: Vec<[f32; 3]> = Vec::new();
        let mut scalars: Vec<f32> = Vec::new();
        let mut tets: Vec<[u32; 4]> = Vec::new();
        for t in 0..per_batch {
            let c = DVec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            let size = rng.range(0.02, 0.5);
            let mut v: [DVec3; 4] =
                std::array::from_fn(|_| c + rng.unit() * size * rng.range(0.3, 1.0));
            // Every 16th tet is made degenerate in projection on purpose.
            let along = |p: DVec3, k: f64| {
                if cam.is_perspective() {
                    eye + (p - eye) * k
                } else {
                    p + fwd * (k - 1.0)
                }
            };
            match t % 64 {
                // An edge along the eye ray: v1 projects onto v0.
                0 => v[1] = along(v[0], 1.0 + rng.range(0.05, 0.3)),
                // A face edge-on: v3 projects onto the segment v1 v2.
                16 => v[3] = along(v[1].lerp(v[2], rng.range(0.2, 0.8)), rng.range(0.9, 1.1)),
                // Flat: all four on one plane through the eye (the projection is a segment).
                32 => {
                    v[2] = along(v[0].lerp(v[1], rng.range(-0.5, 1.5)), rng.range(0.8, 1.2));
                    v[3] = along(v[0].lerp(v[1], rng.range(-0.5, 1.5)), rng.range(0.8, 1.2));
                }
                // v0 projects onto v2 (another pair).
                48 => v[2] = along(v[0], 1.0 - rng.range(0.05, 0.3)),
                _ => {}
            }
            let base = points.len() as u32;
            for p in v {
                points.push([p.x as f32, p.y as f32, p.z as f32]);
                scalars.push(rng.next() as f32);
            }
            tets.push([base, base + 1, base + 2, base + 3]);
        }
        let got = classify_gpu(&gpu, &points, &scalars, &tets, &cam).expect("GPU classification");
        assert_eq!(got.len(), tets.len());
        for (t, g) in tets.iter().zip(&got) {
            let world = t.map(|i| points[i as usize].map(|x| x as f64));
            let s = t.map(|i| scalars[i as usize] as f64);
            let (ndc, c, seg) = classify_tet(&cam, world, s);
            total += 1;
            hist[c.case as usize] += 1;
            let is_degenerate = (total - 1) % 16 == 0;
            degenerate += is_degenerate as usize;
            assert!(g.class == 1 || g.class == 2, "vertex behind the eye? {g:?}");
            assert!(
                g.thick_vertex.iter().all(|v| v.is_finite())
                    && g.length.is_finite()
                    && g.s_front.is_finite()
                    && g.s_back.is_finite(),
                "non-finite GPU output {g:?}"
            );
            if g.case as u8 == c.case {
                case_agree += 1;
            }
            if let Some(rc) = robust_case(ndc) {
                robust += 1;
                robust_generic += !is_degenerate as usize;
                assert_eq!(
                    g.case as u8, rc,
                    "case differs on a robust tet: CPU {c:?}, GPU {g:?}"
                );
                robust_agree += 1;
            }
            // A projection of (numerically) zero area covers no pixel: any thick vertex inside
            // its bounding box is as right as any other.
            let xy = ndc.map(|p| [p[0], p[1]]);
            let screen = (0..4)
                .flat_map(|i| (0..4).map(move |j| (i, j)))
                .map(|(i, j)| (xy[i][0] - xy[j][0]).hypot(xy[i][1] - xy[j][1]))
                .fold(0.0, f64::max);
            let area = hull_area(&xy);
            for k in 0..2 {
                let lo = xy.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
                let hi = xy.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
                let v = g.thick_vertex[k] as f64;
                assert!(
                    v >= lo - 1e-6 && v <= hi + 1e-6,
                    "thick vertex {:?} outside the projection {xy:?}",
                    g.thick_vertex
                );
            }
            // Relative area of the projection: small values are slivers whose thick vertex and
            // thickness are ill-conditioned (f32 rounding of the projection moves them along
            // the sliver by ~ε/area); below 1e-4 they cover a negligible share of any pixel.
            let area_rel = area / (screen * screen);
            if area_rel <= 1e-4 {
                flat += 1;
                continue;
            }
            let diam = (0..4)
                .flat_map(|i| (0..4).map(move |j| (i, j)))
                .map(|(i, j)| (DVec3::from(world[i]) - DVec3::from(world[j])).length())
                .fold(0.0, f64::max);
            let dt = (g.thick_vertex[0] as f64 - c.thick_vertex[0])
                .hypot(g.thick_vertex[1] as f64 - c.thick_vertex[1]);
            let dl = (g.length as f64 - seg.length).abs() / diam;
            let ds = (g.s_front as f64 - seg.s_front)
                .abs()
                .max((g.s_back as f64 - seg.s_back).abs());
            // Front/back may swap on a segment of (near) zero length; compare unordered there.
            let ds = if seg.length < 1e-3 * diam {
                let (a, b) = (
                    g.s_front.min(g.s_back) as f64,
                    g.s_front.max(g.s_back) as f64,
                );
                (a - seg.s_front.min(seg.s_back))
                    .abs()
                    .max((b - seg.s_front.max(seg.s_back)).abs())
            } else {
                ds
            };
            // Geometry agrees everywhere else, ties of the tests included: it is continuous
            // across them. Tolerance: 2e-4 plus the sliver amplification 2e-6 / area.
            let tol = 2e-4 + 2e-6 / area_rel;
            let err = if is_degenerate {
                &mut err_degenerate
            } else {
                &mut err_generic
            };
            err[0] = err[0].max(dt);
            err[1] = err[1].max(dl);
            err[2] = err[2].max(ds);
            assert!(
                dt < tol,
                "thick vertex GPU {:?} CPU {:?} (case {} / {}, relative area {area_rel:.1e})",
                g.thick_vertex,
                c.thick_vertex,
                g.case,
                c.case
            );
            assert!(dl < tol, "length GPU {} CPU {} (diameter {diam}, case {} / {}, relative area {area_rel:.1e})", g.length, seg.length, g.case, c.case);
            assert!(
                ds < 10.0 * tol,
                "scalars GPU {g:?} CPU {seg:?} (relative area {area_rel:.1e})"
            );
        }
    }
    eprintln!(
        "classification: {total} tets ({degenerate} degenerate on purpose), cases {:?}; \
         case agreement {case_agree}/{total} overall, {robust_agree}/{robust} robust; \
         max errors (thick vertex NDC, length / diameter, scalar): generic {}, \
         degenerate {}; {flat} slivers of relative area < 1e-4 (bounds checked only)",
        &hist[1..],
        err_generic.map(|e| format!("{e:.1e}")).join(" / "),
        err_degenerate.map(|e| format!("{e:.1e}")).join(" / ")
    );
    assert!(total >= 100_000);
    assert!(
        hist[1..].iter().all(|&n| n > 0),
        "every case of Table 1 was exercised: {hist:?}"
    );
    let generic = total - degenerate;
    assert!(
        err_generic[0] < 5e-5 && err_generic[1] < 1e-3 && err_generic[2] < 2e-3,
        "generic tets: {err_generic:?}"
    );
    assert!(
        robust_generic as f64 >= 0.99 * generic as f64,
        "too few robust tets: {robust_generic}/{generic}"
    );
}

fn hull_area(p: &[[f64; 2]; 4]) -> f64 {
    let area2 = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs()
    };
    let t = [
        area2(p[1], p[2], p[3]),
        area2(p[0], p[2], p[3]),
        area2(p[0], p[1], p[3]),
        area2(p[0], p[1], p[2]),
    ];
    // Twice the hull area is the largest triangle (one point inside) or half the sum (a quad).
    let max = t.iter().cloned().fold(0.0, f64::max);
    0.5 * max.max(0.5 * t.iter().sum::<f64>())
}

/// Transfer function with constant colour and extinction: then every cell model is exact for
/// orthographic views, because compositing segments of one colour gives c·(1 − e^(−κ·L)) for
/// the total length L whatever the order and the split.
fn constant_optics(mesh: &TetMesh, kappa: f64) -> Optics {
    let tf = TransferFunction {
        name: "constant".into(),
        color: vec![ColorPoint {
            s: 0.0,
            rgb: [0.9, 0.5, 0.2],
        }],
        kappa: vec![KappaPoint { s: 0.0, kappa }],
    };
    Optics::for_mesh(tf, mesh)
}

fn box_mesh(dims: [usize; 3], extent: [f32; 3]) -> TetMesh {
    let mut points = Vec::new();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let f = |n: usize, d: usize, e: f32| n as f32 / (d - 1) as f32 * e - 0.5 * e;
                points.push([
                    f(i, dims[0], extent[0]),
                    f(j, dims[1], extent[1]),
                    f(k, dims[2], extent[2]),
                ]);
            }
        }
    }
    let scalars: Vec<f32> = points.iter().map(|p| p[0] + 2.0 * p[1] - p[2]).collect();
    TetMesh::new(
        "box",
        points,
        scalars,
        "f",
        datasets::volume::structured_tets(dims),
    )
    .expect("valid grid")
}

/// Exact chord length of a ray through an axis-aligned box.
fn chord(origin: DVec3, dir: DVec3, lo: DVec3, hi: DVec3) -> f64 {
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for a in 0..3 {
        if dir[a].abs() < 1e-300 {
            if origin[a] < lo[a] || origin[a] > hi[a] {
                return 0.0;
            }
            continue;
        }
        let (u, v) = ((lo[a] - origin[a]) / dir[a], (hi[a] - origin[a]) / dir[a]);
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
    }
    (t1 - t0).max(0.0)
}

/// Largest error against the closed form c·(1 − e^(−κ·L)) over the pixels whose footprint
/// does not touch the silhouette; also checks every pixel is finite with α in [0, 1].
fn closed_form_error(
    gpu: &Gpu,
    r: &mut GatorPt,
    mesh: &TetMesh,
    kappa: f64,
    vp: &Viewpoint,
    proj: Projection,
) -> f64 {
    let b = mesh.bounds();
    let (lo, hi) = (DVec3::from(b.min), DVec3::from(b.max));
    let cam = Camera::fit(&b, vp, proj, 64, 64);
    r.render(gpu, &cam).unwrap();
    let img = r.read_image(gpu).unwrap();
    let mut worst: f64 = 0.0;
    let mut inside = 0;
    for y in 0..64 {
        for x in 0..64 {
            let p = img.get(x, y);
            assert!(
                p.iter().all(|v| v.is_finite()),
                "{}: NaN/inf at ({x},{y})",
                vp.name
            );
            assert!(p[3] >= -1e-6 && p[3] <= 1.0 + 1e-6);
            let ray = |dx: f64, dy: f64| {
                let r = cam.ray(x as f64 + 0.5 + dx, y as f64 + 0.5 + dy);
                chord(DVec3::from(r.origin), DVec3::from(r.dir), lo, hi)
            };
            let l = ray(0.0, 0.0);
            let near_edge = [(-0.7, -0.7), (0.7, -0.7), (-0.7, 0.7), (0.7, 0.7)]
                .iter()
                .any(|&(dx, dy)| (ray(dx, dy) > 0.0) != (l > 0.0));
            if near_edge {
                continue;
            }
            let alpha = 1.0 - (-kappa * l / b.diagonal()).exp();
            let want = [0.9 * alpha, 0.5 * alpha, 0.2 * alpha, alpha];
            for c in 0..4 {
                worst = worst.max((p[c] as f64 - want[c]).abs());
            }
            inside += (l > 0.0) as usize;
        }
    }
    assert!(inside > 200, "{}: the box covers the view", vp.name);
    worst
}

/// With one colour and one extinction the method is exact for orthographic views (thickness
/// is affine on screen within each fan triangle, and compositing segments of one colour gives
/// c·(1 − e^(−κ·L)) for the total length L). Axis-aligned views of a structured grid are the
/// worst case for degenerate projections (edges along the eye rays project to points, faces
/// edge-on to segments): no NaN, no crack, the closed form to 2e-4 away from the silhouette.
/// Perspective views interpolate the thickness linearly on screen as the paper does, a
/// first-order approximation in (tet depth / view distance): the error must halve, roughly,
/// when the tets halve.
#[test]
fn constant_field_images_are_exact_even_for_degenerate_views() {
    let gpu = gpu();
    let kappa = 2.5;
    let coarse = std::sync::Arc::new(box_mesh([6, 5, 4], [1.0, 0.8, 0.6]));
    let fine = std::sync::Arc::new(box_mesh([11, 9, 7], [1.0, 0.8, 0.6]));
    let oblique = Viewpoint::new("oblique", [0.3, 0.5, 0.8]);
    for cells in [CellModel::Constant, CellModel::Linear] {
        let mut r = GatorPt::new(cells, VisibilityOrder::CentroidRadix);
        r.prepare(&gpu, &coarse, &constant_optics(&coarse, kappa))
            .unwrap();
        let mut views = render_core::fixed_viewpoints();
        views.push(oblique.clone());
        for vp in &views {
            let e = closed_form_error(&gpu, &mut r, &coarse, kappa, vp, Projection::Orthographic);
            assert!(
                e < 2e-4,
                "{cells:?} {} orthographic: max error {e:.2e}",
                vp.name
            );
        }
        for vp in [Viewpoint::new("+x", [1.0, 0.0, 0.0]), oblique.clone()] {
            r.prepare(&gpu, &coarse, &constant_optics(&coarse, kappa))
                .unwrap();
            let e_coarse =
                closed_form_error(&gpu, &mut r, &coarse, kappa, &vp, Projection::default());
            r.prepare(&gpu, &fine, &constant_optics(&fine, kappa))
                .unwrap();
            let e_fine = closed_form_error(&gpu, &mut r, &fine, kappa, &vp, Projection::default());
            eprintln!("{cells:?} {} perspective: max error {e_coarse:.2e} ({} tets), {e_fine:.2e} ({} tets)", vp.name, coarse.num_tets(), fine.num_tets());
            assert!(
                e_coarse < 1.5e-2 && e_fine < 0.65 * e_coarse,
                "{cells:?} {}: {e_coarse:.2e} → {e_fine:.2e}",
                vp.name
            );
        }
    }
}

fn render(
    gpu: &Gpu,
    r: &mut GatorPt,
    mesh: &std::sync::Arc<TetMesh>,
    optics: &Optics,
    cam: &Camera,
) -> Image {
    let prepared = r.prepare(gpu, mesh, optics).unwrap();
    assert_eq!(prepared.tets, mesh.num_tets() as u64);
    assert!(
        prepared.persistent_bytes >= 16 * mesh.num_tets() as u64 + 16 * mesh.num_points() as u64
    );
    let stats = r.render(gpu, cam).unwrap();
    assert!(stats.total_ms > 0.0 && stats.cpu_ms >= 0.0);
    assert!(stats.frame_bytes >= 4 * mesh.num_tets() as u64);
    r.read_image(gpu).unwrap()
}

/// Meshes split over several storage bindings (forced here with 256-byte bindings: 4 tet
/// chunks, 3 point chunks) draw exactly the image of a single binding.
#[test]
fn chunked_bindings_draw_the_same_image() {
    let gpu = gpu();
    // 3·2·2 cells · 5 = 60 tets (16 per 256-byte binding: 4 chunks), 36 points (3 chunks).
    let mesh = std::sync::Arc::new(box_mesh([4, 3, 3], [1.0, 0.8, 0.7]));
    assert_eq!((mesh.num_tets(), mesh.num_points()), (60, 36));
    let tf = TransferFunction::preset("high-opacity").unwrap();
    let optics = Optics::for_mesh(tf, &mesh);
    let cam = Camera::fit(
        &mesh.bounds(),
        &Viewpoint::new("oblique", [0.4, 0.6, 0.7]),
        Projection::default(),
        48,
        48,
    );
    for cells in [CellModel::Constant, CellModel::Linear] {
        let whole = render(
            &gpu,
            &mut GatorPt::new(cells, VisibilityOrder::CentroidRadix),
            &mesh,
            &optics,
            &cam,
        );
        let mut chunked = GatorPt::new(cells, VisibilityOrder::CentroidRadix).with_max_binding(256);
        let split = render(&gpu, &mut chunked, &mesh, &optics, &cam);
        let ledger = chunked.ledger().unwrap();
        let tet_chunks = ledger
            .entries
            .iter()
            .filter(|e| e.0 == "gator tets")
            .count();
        let point_chunks = ledger
            .entries
            .iter()
            .filter(|e| e.0 == "gator points")
            .count();
        assert_eq!((tet_chunks, point_chunks), (4, 3));
        assert_eq!(whole.pixels, split.pixels, "{cells:?}");
        assert!(whole.pixels.iter().any(|p| p[3] > 0.1));
    }
}

/// Centroid distances in f64 ([`Camera::sort_distance`] of each tet's centroid).
fn centroid_distances(mesh: &TetMesh, cam: &Camera) -> Vec<f64> {
    (0..mesh.num_tets())
        .map(|t| {
            let p = mesh.tet_points(t);
            cam.sort_distance([0, 1, 2].map(|a| 0.25 * (p[0][a] + p[1][a] + p[2][a] + p[3][a])))
        })
        .collect()
}

/// `Ok` when `order` is a permutation of the tets whose distances never increase by more than
/// `tol` from one entry to the next (back to front, farthest first).
fn check_back_to_front(order: &[u32], dist: &[f64], tol: f64) -> Result<(), String> {
    let mut seen = order.to_vec();
    seen.sort_unstable();
    if seen != (0..dist.len() as u32).collect::<Vec<_>>() {
        return Err(format!(
            "not a permutation of 0..{} ({} entries)",
            dist.len(),
            order.len()
        ));
    }
    match order
        .windows(2)
        .position(|w| dist[w[1] as usize] > dist[w[0] as usize] + tol)
    {
        Some(i) => Err(format!(
            "position {i}: tet {} at {} before tet {} at {}",
            order[i],
            dist[order[i] as usize],
            order[i + 1],
            dist[order[i + 1] as usize]
        )),
        None => Ok(()),
    }
}

/// The order `sort=gpu-radix` makes on the device (read back through the debug hook after a
/// frame) is a permutation of 0..n sorted back to front by the f64 centroid distances, up to
/// the keys' f32 rounding (1e-5 of the largest distance), from perspective and orthographic
/// views, in one tet binding and over two. The check can fail: the same order reversed (front
/// to back) does. The frame counts its sort as GPU work, times it on the GPU and counts the
/// keys and the sorter's scratch as per-frame device bytes.
#[test]
fn gpu_radix_order_is_a_back_to_front_permutation() {
    let gpu = gpu();
    // 11·9·8 cells · 5 = 3,960 tets; 1,080 points (17,280 bytes: one binding of 32 KiB, where
    // 2,048 tets fit, so the tets take two).
    let mesh = std::sync::Arc::new(box_mesh([12, 10, 9], [1.0, 0.8, 0.7]));
    assert_eq!((mesh.num_tets(), mesh.num_points()), (3960, 1080));
    let n = mesh.num_tets() as u64;
    let optics = Optics::for_mesh(TransferFunction::preset("low-opacity").unwrap(), &mesh);
    let views = [
        (
            Viewpoint::new("oblique", [0.4, 0.6, 0.7]),
            Projection::default(),
        ),
        (
            Viewpoint::new("-x+y-z", [-1.0, 1.0, -1.0]),
            Projection::default(),
        ),
        (
            Viewpoint::new("oblique", [0.3, -0.8, 0.5]),
            Projection::Orthographic,
        ),
        (
            Viewpoint::new("+z", [0.0, 0.0, 1.0]),
            Projection::Orthographic,
        ),
    ];
    for max_binding in [None, Some(32 << 10)] {
        let mut r = GatorPt::new(CellModel::Linear, GatorSort::GpuRadix);
        if let Some(b) = max_binding {
            r = r.with_max_binding(b);
        }
        r.prepare(&gpu, &mesh, &optics).unwrap();
        let ledger = r.ledger().unwrap().clone();
        let chunks = ledger
            .entries
            .iter()
            .filter(|e| e.0 == "gator tets")
            .count();
        assert_eq!(chunks, if max_binding.is_some() { 2 } else { 1 });
        // Keys (4 B a tet) and the sorter's ping-pong copies (8 B a tet), per frame.
        assert_eq!(ledger.bytes_labelled("gator sort keys"), 4 * n);
        assert!(ledger.bytes_labelled("radix sort") >= 8 * n);
        for (vp, projection) in &views {
            let cam = Camera::fit(&mesh.bounds(), vp, *projection, 64, 64);
            let stats = r.render(&gpu, &cam).unwrap();
            let order = r.debug_read_order(&gpu).unwrap();
            let dist = centroid_distances(&mesh, &cam);
            let scale = dist.iter().fold(0.0f64, |m, d| m.max(d.abs()));
            let tol = 1e-5 * scale;
            let what = format!("{} {projection:?}, max binding {max_binding:?}", vp.name);
            check_back_to_front(&order, &dist, tol).unwrap_or_else(|e| panic!("{what}: {e}"));
            let reversed: Vec<u32> = order.iter().rev().copied().collect();
            assert!(
                check_back_to_front(&reversed, &dist, tol).is_err(),
                "{what}: front to back passes the check"
            );
            let counter = |name: &str| {
                stats
                    .counters
                    .iter()
                    .find(|(c, _)| c == name)
                    .map(|(_, v)| *v)
            };
            assert_eq!(counter("gpu_sort_keys"), Some(n as f64), "{what}");
            assert_eq!(counter("cpu_sort_keys"), None, "{what}");
            let stage = |name: &str| stats.stages.iter().any(|(s, _)| s == name);
            assert!(!stage("sort") && !stage("sort_precompute"), "{what}");
            if stats.gpu_ms.is_some() {
                assert!(
                    stage("gpu_sort") && stage("draw"),
                    "{what}: {:?}",
                    stats.stages
                );
            }
            // The order (4 B a tet), the keys and the sort's scratch.
            assert!(
                stats.frame_bytes
                    >= 4 * n
                        + ledger.bytes_labelled("gator sort keys")
                        + ledger.bytes_labelled("radix sort"),
                "{what}: {} frame bytes",
                stats.frame_bytes
            );
        }
    }
}

/// `sort=gpu-radix` with its tets split over three storage bindings (1 KiB each: 64 tets, and
/// the 64 points in one) draws exactly the image of one binding: the key pass writes each
/// chunk's keys and ids at their place. A mesh whose points need more than one binding is
/// refused in prepare, naming the mesh and why, while a CPU order draws it.
#[test]
fn gpu_radix_over_several_tet_bindings_draws_the_same_image() {
    let gpu = gpu();
    // 3·3·3 cells · 5 = 135 tets (3 chunks of 64), 64 points (one chunk of 64).
    let mesh = std::sync::Arc::new(box_mesh([4, 4, 4], [1.0, 0.8, 0.7]));
    assert_eq!((mesh.num_tets(), mesh.num_points()), (135, 64));
    let tf = TransferFunction::preset("high-opacity").unwrap();
    let optics = Optics::for_mesh(tf, &mesh);
    for (vp, projection) in [
        (
            Viewpoint::new("oblique", [0.4, 0.6, 0.7]),
            Projection::default(),
        ),
        (
            Viewpoint::new("-x-y+z", [-1.0, -1.0, 1.0]),
            Projection::Orthographic,
        ),
    ] {
        let cam = Camera::fit(&mesh.bounds(), &vp, projection, 48, 48);
        for cells in [CellModel::Constant, CellModel::Linear] {
            let whole = render(
                &gpu,
                &mut GatorPt::new(cells, GatorSort::GpuRadix),
                &mesh,
                &optics,
                &cam,
            );
            let mut chunked = GatorPt::new(cells, GatorSort::GpuRadix).with_max_binding(1024);
            let split = render(&gpu, &mut chunked, &mesh, &optics, &cam);
            let ledger = chunked.ledger().unwrap();
            let count = |label: &str| ledger.entries.iter().filter(|e| e.0 == label).count();
            assert_eq!((count("gator tets"), count("gator points")), (3, 1));
            assert!(whole.pixels.iter().any(|p| p[3] > 0.1));
            assert!(
                whole.pixels == split.pixels,
                "{cells:?} {}: the chunked GPU sort's image differs",
                vp.name
            );
        }
    }
    // 36 points over 16-point bindings: three, where the key pass reads one.
    let wide = std::sync::Arc::new(box_mesh([4, 3, 3], [1.0, 0.8, 0.7]));
    let mut r = GatorPt::new(CellModel::Linear, GatorSort::GpuRadix).with_max_binding(256);
    let e = format!("{:#}", r.prepare(&gpu, &wide, &optics).unwrap_err());
    assert!(
        e.contains("mesh box") && e.contains("36 points") && e.contains("one storage binding"),
        "{e}"
    );
    let mut cpu =
        GatorPt::new(CellModel::Linear, VisibilityOrder::CentroidRadix).with_max_binding(256);
    cpu.prepare(&gpu, &wide, &optics).unwrap();
}

#[test]
fn settings_and_variants() {
    let v = gator_pt::DESCRIPTION.default_variants().unwrap();
    let rows: Vec<String> = v.iter().map(|r| r.settings().to_string()).collect();
    assert_eq!(
        rows,
        ["variant=constant;sort=radix", "variant=linear;sort=radix"]
    );
    assert!(v.iter().all(|r| r.algorithm() == "gator-pt"));
    // The device sort is in the full grid only (the paper sorts on the CPU), and builds from
    // its text.
    let d = &gator_pt::DESCRIPTION;
    let gpu_radix = d.parse_settings("variant=linear;sort=gpu-radix").unwrap();
    assert!((d.full_grid)().contains(&gpu_radix));
    assert!(!(d.default_grid)().contains(&gpu_radix));
    assert_eq!((d.build)(&gpu_radix).unwrap().settings(), gpu_radix);
    assert_eq!(
        "gpu-radix".parse::<GatorSort>().unwrap(),
        GatorSort::GpuRadix
    );
    assert_eq!(
        "mpvonc".parse::<GatorSort>().unwrap(),
        GatorSort::Cpu(VisibilityOrder::Mpvonc)
    );
    let e = "gpu".parse::<GatorSort>().unwrap_err().to_string();
    assert!(e.contains("gpu-radix"), "{e}");
}

/// The debug classification read back in chunks (a binding of a few hundred records, so a
/// small mesh needs several dispatches) is the one-chunk readback record for record, in mesh
/// order; its recorded test outcomes spell its case (case = 2·(4·t1 + 2·t2 + t3) + 1 + t4, 13
/// and 14 where t1 and t2 hold) and its screen points are the projection the twin computes.
#[test]
fn the_debug_classification_reads_back_in_chunks_in_mesh_order() {
    use gator_pt::GpuClassifier;
    let gpu = gpu();
    let mesh = datasets::registry::Registry::new(None)
        .resolve("box:2k", &datasets::LoadOptions::default())
        .expect("generated mesh")
        .mesh;
    let cam = Camera::fit(
        &mesh.bounds(),
        &render_core::fixed_viewpoints()[6],
        Default::default(),
        512,
        512,
    );
    let scalars = mesh.scalars.clone();
    let mut one = GpuClassifier::new(&gpu, &mesh.points, &scalars, &mesh.tets, None).unwrap();
    let mut chunked =
        GpuClassifier::new(&gpu, &mesh.points, &scalars, &mesh.tets, Some(256 * 80)).unwrap();
    assert!(chunked.tets_per_chunk() < mesh.tets.len() as u64 / 4);
    let a = one.classify(&gpu, &cam).unwrap();
    let b = chunked.classify(&gpu, &cam).unwrap();
    assert_eq!(a.len(), mesh.tets.len());
    assert_eq!(a, b);
    let m = cam.view_proj();
    for (t, g) in mesh.tets.iter().zip(&a) {
        let [t1, t2, t3, t4] = g.test_outcomes();
        let idx = 4 * t1 as u32 + 2 * t2 as u32 + t3 as u32;
        let case = if idx < 6 {
            2 * idx + 1 + t4 as u32
        } else {
            13 + idx - 6
        };
        assert_eq!(g.case, case, "{g:?}");
        for (k, &v) in t.iter().enumerate() {
            let p = DVec3::from(mesh.points[v as usize].map(f64::from));
            let c = m * p.extend(1.0);
            assert!((g.screen_x[k] as f64 - c.x / c.w).abs() < 1e-5, "{g:?}");
            assert!((g.screen_y[k] as f64 - c.y / c.w).abs() < 1e-5, "{g:?}");
        }
    }
}
