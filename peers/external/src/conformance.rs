//! `tetbench external check`: a renderer against the exact reference on a tiny asymmetric
//! mesh, in views chosen so that each convention of the protocol shows (orientation,
//! handedness, premultiplied colour, vertical field of view, pixel centres, extinction units,
//! an empty view), and a timing sanity check. A failed view is compared with the reference
//! transformed by each known mistake; the one that explains the image is named in plain words.
//!
//! Works on any [`Renderer`], so tetbench's own algorithms and the VTK peers can be checked
//! the same way.

use std::path::Path;

use datasets::TetMesh;
use render_core::image::linear_to_srgb;
use render_core::image_error::psnr_from_rmse;
use render_core::{
    Camera, DeclaredAccuracy, FrameStats, Gpu, Image, Optics, Projection, Renderer,
    TransferFunction, Viewpoint,
};

/// A view passes at this PSNR (RGBA, see [`psnr_rgba`]) against the reference.
pub const PASS_DB: f64 = 35.0;

/// The lowest accuracy a renderer may declare ([`DeclaredAccuracy`]): every gross convention
/// mistake of [`mistakes`] costs more than this on the check's views, and below it an
/// approximation could hide them.
pub const LOWEST_DECLARED_DB: f64 = 20.0;

/// A transformed reference explains a failed image when the image is at least this close to it…
const EXPLAINED_DB: f64 = 30.0;
/// …and this much closer to it than to the reference.
const EXPLAINED_MARGIN_DB: f64 = 3.0;

/// The outcome of one view (or of the timing check).
#[derive(Debug, Clone, PartialEq)]
pub struct CaseResult {
    pub name: String,
    pub passed: bool,
    /// PSNR against the reference, when an image was compared.
    pub psnr_db: Option<f64>,
    /// What was found, in plain words.
    pub message: String,
}

/// Every case of one check.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CheckReport {
    pub cases: Vec<CaseResult>,
}

impl CheckReport {
    pub fn passed(&self) -> bool {
        !self.cases.is_empty() && self.cases.iter().all(|c| c.passed)
    }

    pub fn failures(&self) -> impl Iterator<Item = &CaseResult> {
        self.cases.iter().filter(|c| !c.passed)
    }
}

impl std::fmt::Display for CheckReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for c in &self.cases {
            writeln!(
                f,
                "{} {}: {}",
                if c.passed { "PASS" } else { "FAIL" },
                c.name,
                c.message
            )?;
        }
        Ok(())
    }
}

/// The test mesh: an L-shaped block (a 4 × 3 × 2 grid of boxes with the +x+y corner column
/// removed), so every flip and turn of its image differs; 6 tets per box (Kuhn's split, which
/// conforms between neighbours); the scalar rises along x, y and z at different rates. Its
/// diagonal is about 4.3, so extinction per world unit and per diagonal differ.
pub fn l_mesh() -> TetMesh {
    let (nx, ny, nz) = (4usize, 3usize, 2usize);
    let size = [0.8f32, 0.9, 0.7];
    let id = |i: usize, j: usize, k: usize| (i + (nx + 1) * (j + (ny + 1) * k)) as u32;
    let mut points = vec![];
    let mut scalars = vec![];
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                let p = [i as f32 * size[0], j as f32 * size[1], k as f32 * size[2]];
                points.push(p);
                scalars.push(p[0] + 0.6 * p[1] + 0.3 * p[2] * p[2]);
            }
        }
    }
    let mut tets = vec![];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                if i >= 2 && j >= 2 {
                    continue; // the notch that makes the L
                }
                let corner = |b: usize| id(i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1));
                // Kuhn: the six monotone paths from corner 0 to corner 7.
                for perm in [
                    [0, 1, 2],
                    [0, 2, 1],
                    [1, 0, 2],
                    [1, 2, 0],
                    [2, 0, 1],
                    [2, 1, 0],
                ] {
                    let mut b = 0usize;
                    let mut t = [corner(0); 4];
                    for (n, axis) in perm.iter().enumerate() {
                        b |= 1 << axis;
                        t[n + 1] = corner(b);
                    }
                    tets.push(t);
                }
            }
        }
    }
    TetMesh::new("conformance-L", points, scalars, "s", tets).expect("the L mesh is valid")
}

/// One view of the check.
struct Case {
    name: &'static str,
    camera: Camera,
    /// What this view is for, said when it passes.
    purpose: &'static str,
}

fn fitted(mesh: &TetMesh, dir: [f64; 3], projection: Projection, w: u32, h: u32) -> Camera {
    Camera::fit(
        &mesh.bounds(),
        &Viewpoint::new("check", dir),
        projection,
        w,
        h,
    )
}

fn cases(mesh: &TetMesh) -> Vec<Case> {
    let oblique = [0.35, 0.45, 1.0];
    let mut off = fitted(mesh, [-0.3, 0.25, 1.0], Projection::default(), 40, 40);
    // Pan: the mesh moves towards a corner of the image.
    let r = 0.5 * mesh.bounds().diagonal();
    let f = glam::DVec3::from(off.forward());
    let right = f.cross(glam::DVec3::from(off.up)).normalize();
    let up = right.cross(f);
    let shift = right * (0.35 * r) - up * (0.25 * r);
    off.eye = (glam::DVec3::from(off.eye) + shift).into();
    off.target = (glam::DVec3::from(off.target) + shift).into();
    let mut empty = fitted(mesh, oblique, Projection::default(), 32, 24);
    // Turned away: the mesh is behind the camera.
    let eye = glam::DVec3::from(empty.eye);
    empty.target = (eye + (eye - glam::DVec3::from(mesh.bounds().center()))).into();
    vec![
        Case {
            name: "perspective",
            camera: fitted(mesh, oblique, Projection::default(), 48, 32),
            purpose: "orientation, handedness, premultiplied colour, vertical field of view",
        },
        Case {
            name: "orthographic",
            camera: fitted(mesh, oblique, Projection::Orthographic, 48, 32),
            purpose: "orthographic extent",
        },
        Case {
            name: "off-centre",
            camera: off,
            purpose: "target away from the mesh centre",
        },
        Case {
            name: "pixel-centres",
            camera: fitted(mesh, [0.0, 0.0, 1.0], Projection::Orthographic, 20, 14),
            purpose: "pixel centres at (x+½, y+½), extinction units",
        },
        Case {
            name: "empty",
            camera: empty,
            purpose: "the mesh behind the camera: transparent black",
        },
    ]
}

/// RMSE over all four channels (colour and alpha: a wrong background alpha must show), each
/// clamped to [0, 1].
pub fn rmse_rgba(a: &Image, b: &Image) -> f64 {
    let n = a.pixels.len().max(1) as f64;
    let sum: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..4).map(move |c| render_core::image_error::channel_error(p[c], q[c])))
        .map(|d| d * d)
        .sum();
    (sum / (4.0 * n)).sqrt()
}

/// PSNR of [`rmse_rgba`] (peak 1, capped at 99 dB).
pub fn psnr_rgba(a: &Image, b: &Image) -> f64 {
    psnr_from_rmse(rmse_rgba(a, b))
}

fn map_pixels(img: &Image, mut f: impl FnMut([f32; 4]) -> [f32; 4]) -> Image {
    Image {
        width: img.width,
        height: img.height,
        pixels: img.pixels.iter().map(|&p| f(p)).collect(),
    }
}

fn remap(img: &Image, flip_x: bool, flip_y: bool) -> Image {
    let (w, h) = (img.width, img.height);
    let mut out = Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let sx = if flip_x { w - 1 - x } else { x };
            let sy = if flip_y { h - 1 - y } else { y };
            out.set(x, y, img.get(sx, sy));
        }
    }
    out
}

/// The image a W×H texture shows when it is drawn with its first and last texel centres on the
/// viewport's edges: pixel centre x + ½ samples texel (x + ½)(W − 1)/W, bilinearly.
fn texture_scaled(img: &Image) -> Image {
    let (w, h) = (img.width, img.height);
    let mut out = Image::new(w, h);
    let coord = |x: u32, n: u32| {
        let u = (x as f64 + 0.5) * (n as f64 - 1.0) / n as f64;
        let i = (u.floor() as u32).min(n.saturating_sub(2));
        (i, (u - i as f64) as f32)
    };
    for y in 0..h {
        let (j, fy) = coord(y, h);
        for x in 0..w {
            let (i, fx) = coord(x, w);
            let at = |dx: u32, dy: u32| img.get((i + dx).min(w - 1), (j + dy).min(h - 1));
            let (a, b, c, d) = (at(0, 0), at(1, 0), at(0, 1), at(1, 1));
            let mut p = [0f32; 4];
            for k in 0..4 {
                let top = a[k] + fx * (b[k] - a[k]);
                let bottom = c[k] + fx * (d[k] - c[k]);
                p[k] = top + fy * (bottom - top);
            }
            out.set(x, y, p);
        }
    }
    out
}

/// The reference as one known mistake would show it.
struct Mistake {
    /// What is wrong, in plain words.
    what: String,
    image: Image,
    /// A shift or scaling by a fraction of a pixel: smaller than the error of a renderer that
    /// declares an approximate geometry, so not judged under a [`DeclaredAccuracy`].
    sub_pixel: bool,
}

/// The reference as each known mistake would show it.
fn mistakes(mesh: &TetMesh, optics: &Optics, camera: &Camera, reference: &Image) -> Vec<Mistake> {
    let mut m: Vec<(String, Image)> = vec![
        (
            "image is upside down (row 0 must be the top of the image)".into(),
            remap(reference, false, true),
        ),
        (
            "image is mirrored left-right (the camera is right-handed: right = forward × up)"
                .into(),
            remap(reference, true, false),
        ),
        (
            "image is rotated by 180°".into(),
            remap(reference, true, true),
        ),
        (
            "colour is not premultiplied (RGB must be multiplied by alpha)".into(),
            map_pixels(reference, |p| {
                if p[3] > 1e-6 {
                    [p[0] / p[3], p[1] / p[3], p[2] / p[3], p[3]]
                } else {
                    p
                }
            }),
        ),
        (
            "colour is premultiplied twice (RGB multiplied by alpha once too often)".into(),
            map_pixels(reference, |p| [p[0] * p[3], p[1] * p[3], p[2] * p[3], p[3]]),
        ),
        (
            "red and blue are swapped (channels must be R, G, B, A)".into(),
            map_pixels(reference, |p| [p[2], p[1], p[0], p[3]]),
        ),
        (
            "colour is sRGB-encoded, expected linear".into(),
            map_pixels(reference, |p| {
                [
                    linear_to_srgb(p[0]),
                    linear_to_srgb(p[1]),
                    linear_to_srgb(p[2]),
                    p[3],
                ]
            }),
        ),
    ];
    if let Projection::Perspective { fovy_deg } = camera.projection {
        if camera.width != camera.height {
            // fovy_deg taken as the horizontal angle: the vertical one is narrower (or wider).
            let aspect = camera.width as f64 / camera.height as f64;
            let vertical = 2.0 * ((fovy_deg.to_radians() * 0.5).tan() / aspect).atan();
            let mut c = camera.clone();
            c.projection = Projection::Perspective {
                fovy_deg: vertical.to_degrees(),
            };
            m.push((
                "field of view is horizontal, expected vertical".into(),
                reference::render(mesh, optics, &c),
            ));
        }
    } else {
        // Rays through pixel corners (x, y) instead of centres: the same as the camera moved
        // half a pixel left and up (exact for an orthographic camera).
        let mut c = camera.clone();
        let f = glam::DVec3::from(c.forward());
        let right = f.cross(glam::DVec3::from(c.up)).normalize();
        let up = right.cross(f);
        let px = 2.0 * c.ortho_half_height / c.height as f64;
        let shift = -right * (0.5 * px) + up * (0.5 * px);
        c.eye = (glam::DVec3::from(c.eye) + shift).into();
        c.target = (glam::DVec3::from(c.target) + shift).into();
        m.push((
            "pixels are sampled at their corners, expected at their centres (x+½, y+½)".into(),
            reference::render(mesh, optics, &c),
        ));
    }
    m.push((
        "image is scaled by (W−1)/W about its centre (drawn as a texture whose texel centres \
         sit on the viewport's edges, as VTK displays its ray caster's and ZSweep's image)"
            .into(),
        texture_scaled(reference),
    ));
    let mut world = optics.clone();
    world.length_unit = 1.0;
    m.push((
        "extinction is per world unit, expected per unit of the bounding-box diagonal \
         (length_unit)"
            .into(),
        reference::render(mesh, &world, camera),
    ));
    m.into_iter()
        .map(|(what, image)| Mistake {
            sub_pixel: what.starts_with("pixels are sampled at their corners")
                || what.starts_with("image is scaled by (W−1)/W"),
            what,
            image,
        })
        .collect()
}

/// Judges one image against its reference; `Ok` with what passed, `Err` with what is wrong.
///
/// With a [`DeclaredAccuracy`], a view below [`PASS_DB`] but at or above the declared PSNR
/// passes only if the image is nearer the reference than the reference as each gross
/// convention mistake would show it (orientation, handedness, alpha, channels, sRGB, field of
/// view, extinction units): an approximation adds error in every direction, a convention
/// mistake moves the image towards that mistake, so the nearest of the two names it.
fn judge(
    mesh: &TetMesh,
    optics: &Optics,
    camera: &Camera,
    image: &Image,
    reference: &Image,
    declared: Option<&DeclaredAccuracy>,
    out: Option<(&Path, &str)>,
) -> (f64, Result<String, String>) {
    let psnr = psnr_rgba(image, reference);
    let lit = |img: &Image| {
        img.pixels
            .iter()
            .filter(|p| p.iter().any(|v| v.abs() > 1e-4))
            .count()
    };
    if lit(reference) == 0 {
        let n = lit(image);
        return if n == 0 {
            (psnr, Ok("transparent black, as expected".into()))
        } else {
            (
                psnr,
                Err(format!(
                    "the empty view is not transparent black: {n} of {} pixels are not \
                     (0, 0, 0, 0) (the mesh is behind the camera; a background or alpha written \
                     where no ray hits, or geometry behind the eye drawn)",
                    image.pixels.len()
                )),
            )
        };
    }
    if psnr >= PASS_DB {
        return (psnr, Ok(format!("PSNR {psnr:.1} dB")));
    }
    if lit(image) == 0 {
        return (
            psnr,
            Err("image is empty (transparent black) where the mesh should be".into()),
        );
    }
    let candidates = mistakes(mesh, optics, camera, reference);
    let nearest = |gross_only: bool| {
        candidates
            .iter()
            .filter(|m| !(gross_only && m.sub_pixel))
            .map(|m| (m, psnr_rgba(image, &m.image)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .expect("there are candidates")
    };
    if let Some(d) = declared.filter(|d| psnr >= d.min_psnr_db) {
        let (m, db) = nearest(true);
        return if db > psnr {
            (
                psnr,
                Err(format!(
                    "{} (PSNR {psnr:.1} dB against the reference, {db:.1} dB against the \
                     reference with this mistake: nearer the mistake, which the declared \
                     accuracy of {:.1} dB does not excuse)",
                    m.what, d.min_psnr_db
                )),
            )
        } else {
            (
                psnr,
                Ok(format!(
                    "PSNR {psnr:.1} dB, within the declared {:.1} dB and nearer the reference \
                     than any convention mistake (closest: {db:.1} dB; sub-pixel conventions \
                     not judged at this accuracy)",
                    d.min_psnr_db
                )),
            )
        };
    }
    let (best, best_db) = nearest(false);
    let best = (&best.what, &best.image, best_db);
    if let Some((dir, stem)) = out {
        let _ = best
            .1
            .save_png(&dir.join(format!("{stem}.closest-mistake.png")));
    }
    let message = if best.2 >= EXPLAINED_DB && best.2 >= psnr + EXPLAINED_MARGIN_DB {
        format!(
            "{} (PSNR {psnr:.1} dB against the reference, {:.1} dB against the reference with \
             this mistake)",
            best.0, best.2
        )
    } else {
        format!(
            "image differs from the reference: PSNR {psnr:.1} dB, {PASS_DB} dB needed; no known \
             convention mistake explains it (closest: \"{}\" at {:.1} dB)",
            best.0, best.2
        )
    };
    (psnr, Err(message))
}

/// Timing sanity of one frame: what is impossible about its times, if anything.
fn timing_problem(f: &FrameStats) -> Option<String> {
    let ok = |v: f64| v.is_finite() && v >= 0.0;
    if !ok(f.total_ms) || f.total_ms <= 0.0 {
        return Some(format!("the frame took {} ms", f.total_ms));
    }
    let stage = |k: &str| f.stages.iter().find(|(n, _)| n == k).map(|(_, v)| *v);
    let wall = stage("renderer_wall_ms");
    if let Some(w) = wall {
        // tetbench's own clock ran around the renderer's: a longer frame is impossible.
        // A NaN time fails as well as a non-positive or too long one.
        if w.is_nan() || w <= 0.0 || w > f.total_ms + 1.0 {
            return Some(format!(
                "wall_ms = {w:.3} but tetbench timed the whole exchange at {:.3} ms (wall_ms \
                 must be positive and no longer than that)",
                f.total_ms
            ));
        }
    }
    let limit = wall.unwrap_or(f.total_ms) * 1.01 + 0.5;
    if let Some(c) = stage("renderer_cpu_ms").filter(|&c| c > limit) {
        return Some(format!(
            "cpu_ms = {c:.3} is longer than the frame ({limit:.3} ms)"
        ));
    }
    if let Some(g) = f.gpu_ms.filter(|&g| !ok(g) || g > limit) {
        return Some(format!(
            "gpu_ms = {g:.3} is longer than the frame ({limit:.3} ms)"
        ));
    }
    None
}

/// Runs the whole check on `renderer`; `out` receives the images (PNG) when given.
pub fn check(
    renderer: &mut dyn Renderer,
    gpu: &Gpu,
    out: Option<&Path>,
) -> anyhow::Result<CheckReport> {
    if let Some(dir) = out {
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", dir.display()))?;
    }
    let mesh = std::sync::Arc::new(l_mesh());
    let optics = Optics::for_mesh(
        TransferFunction::preset("low-opacity").expect("a preset"),
        &mesh,
    );
    let mut report = CheckReport::default();
    if let Err(e) = renderer.prepare(gpu, &mesh, &optics) {
        report.cases.push(CaseResult {
            name: "prepare".into(),
            passed: false,
            psnr_db: None,
            message: format!("{e:#}"),
        });
        return Ok(report);
    }
    let declared = renderer.declared_accuracy();
    if let Some(d) = &declared {
        report.cases.push(CaseResult {
            name: "declared accuracy".into(),
            passed: true,
            psnr_db: None,
            message: format!(
                "{:.1} dB ({}): a view between it and {PASS_DB} dB passes only when it is nearer \
                 the reference than every gross convention mistake",
                d.min_psnr_db, d.reason
            ),
        });
    }
    let mut timing = vec![];
    let mut frames = 0;
    for case in cases(&mesh) {
        let cam = &case.camera;
        let name = format!("{} ({}×{})", case.name, cam.width, cam.height);
        let rendered = renderer
            .render(gpu, cam)
            .and_then(|f| Ok((f, renderer.read_image(gpu)?)));
        let (stats, image) = match rendered {
            Ok(r) => r,
            Err(e) => {
                report.cases.push(CaseResult {
                    name,
                    passed: false,
                    psnr_db: None,
                    message: format!("{e:#}"),
                });
                continue;
            }
        };
        frames += 1;
        if let Some(p) = timing_problem(&stats) {
            timing.push(format!("{}: {p}", case.name));
        }
        if (image.width, image.height) != (cam.width, cam.height) {
            report.cases.push(CaseResult {
                name,
                passed: false,
                psnr_db: None,
                message: format!(
                    "image is {}×{}, the viewport {}×{}",
                    image.width, image.height, cam.width, cam.height
                ),
            });
            continue;
        }
        let reference = reference::render(&mesh, &optics, cam);
        if let Some(dir) = out {
            let _ = image.save_png(&dir.join(format!("{}.png", case.name)));
            let _ = reference.save_png(&dir.join(format!("{}.reference.png", case.name)));
        }
        let (psnr, verdict) = judge(
            &mesh,
            &optics,
            cam,
            &image,
            &reference,
            declared.as_ref(),
            out.map(|d| (d, case.name)),
        );
        report.cases.push(CaseResult {
            name,
            passed: verdict.is_ok(),
            psnr_db: Some(psnr),
            message: match verdict {
                Ok(m) => format!("{m} — {}", case.purpose),
                Err(m) => m,
            },
        });
    }
    report.cases.push(CaseResult {
        name: "timing".into(),
        passed: timing.is_empty() && frames > 0,
        psnr_db: None,
        message: if frames == 0 {
            "no frame was rendered".into()
        } else if timing.is_empty() {
            format!("{frames} frames with plausible times")
        } else {
            timing.join("; ")
        },
    });
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> (TetMesh, Optics, Vec<Case>) {
        let mesh = l_mesh();
        let optics = Optics::for_mesh(TransferFunction::preset("low-opacity").unwrap(), &mesh);
        let cases = cases(&mesh);
        (mesh, optics, cases)
    }

    #[test]
    fn the_l_mesh_is_asymmetric_and_its_views_see_it() {
        let (mesh, optics, cases) = scene();
        assert_eq!(mesh.num_tets(), (4 * 3 * 2 - 2 * 2) * 6);
        assert!(!mesh.is_convex());
        for case in &cases {
            let r = reference::render(&mesh, &optics, &case.camera);
            let lit = r.pixels.iter().filter(|p| p[3] > 1e-3).count();
            if case.name == "empty" {
                assert_eq!(lit, 0);
                continue;
            }
            assert!(lit > r.pixels.len() / 5, "{}: {lit} lit pixels", case.name);
            // No flip of the image looks like the image.
            for (fx, fy) in [(true, false), (false, true), (true, true)] {
                assert!(
                    psnr_rgba(&remap(&r, fx, fy), &r) < 25.0,
                    "{} {fx} {fy}",
                    case.name
                );
            }
        }
    }

    /// Every mistake the check names is recognised when the image is exactly that mistake (in
    /// every view where it matters, and at least one view for each), and the reference itself
    /// passes: the verdicts flip with the input.
    #[test]
    fn each_mistake_is_named_when_made() {
        let (mesh, optics, cases) = scene();
        let mut named: Vec<String> = vec![];
        for case in cases.iter().filter(|c| c.name != "empty") {
            let r = reference::render(&mesh, &optics, &case.camera);
            let (_, ok) = judge(&mesh, &optics, &case.camera, &r, &r, None, None);
            assert!(ok.is_ok(), "{}: {ok:?}", case.name);
            for Mistake {
                what, image: wrong, ..
            } in mistakes(&mesh, &optics, &case.camera, &r)
            {
                if psnr_rgba(&wrong, &r) >= PASS_DB {
                    continue; // too small to matter in this view
                }
                let (_, verdict) = judge(&mesh, &optics, &case.camera, &wrong, &r, None, None);
                let msg = verdict.expect_err(&format!("{}: {what} passed", case.name));
                assert!(
                    msg.starts_with(&what),
                    "{}: expected {what:?}, got {msg:?}",
                    case.name
                );
                named.push(what);
            }
        }
        named.sort();
        named.dedup();
        assert_eq!(named.len(), 11, "{named:#?}");
    }

    #[test]
    fn an_empty_view_with_a_background_fails() {
        let (mesh, optics, cases) = scene();
        let case = cases.iter().find(|c| c.name == "empty").unwrap();
        let r = reference::render(&mesh, &optics, &case.camera);
        assert!(judge(&mesh, &optics, &case.camera, &r, &r, None, None)
            .1
            .is_ok());
        let opaque = map_pixels(&r, |_| [0.0, 0.0, 0.0, 1.0]);
        let msg = judge(&mesh, &optics, &case.camera, &opaque, &r, None, None)
            .1
            .unwrap_err();
        assert!(msg.contains("not transparent black"), "{msg}");
    }

    #[test]
    fn impossible_times_are_named() {
        let f = |total: f64, wall: f64, cpu: Option<f64>, gpu: Option<f64>| {
            let mut stages = vec![("renderer_wall_ms".to_string(), wall)];
            if let Some(c) = cpu {
                stages.push(("renderer_cpu_ms".to_string(), c));
            }
            FrameStats {
                total_ms: total,
                cpu_ms: total,
                gpu_ms: gpu,
                stages,
                ..Default::default()
            }
        };
        assert_eq!(timing_problem(&f(10.0, 9.0, Some(5.0), Some(8.0))), None);
        assert!(timing_problem(&f(10.0, 20.0, None, None))
            .unwrap()
            .contains("wall_ms"));
        assert!(timing_problem(&f(10.0, 0.0, None, None))
            .unwrap()
            .contains("wall_ms"));
        assert!(timing_problem(&f(10.0, 5.0, Some(9.0), None))
            .unwrap()
            .contains("cpu_ms"));
        assert!(timing_problem(&f(10.0, 5.0, None, Some(9.0)))
            .unwrap()
            .contains("gpu_ms"));
        assert!(timing_problem(&f(f64::NAN, 5.0, None, None)).is_some());
    }

    /// An approximate renderer's error: deterministic noise of ±`amp` on every channel of every
    /// lit pixel (clamped to [0, 1]).
    fn noisy(img: &Image, amp: f32) -> Image {
        let mut state = 0x2545_f491u32;
        let mut next = move || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
        };
        map_pixels(img, |p| {
            if p.iter().all(|&v| v.abs() < 1e-4) {
                return p;
            }
            p.map(|v| (v + amp * next()).clamp(0.0, 1.0))
        })
    }

    /// Under a declared accuracy an approximate image (the reference plus noise, below 35 dB)
    /// passes, and fails without the declaration; each gross convention mistake with the same
    /// noise still fails and is named, also where its PSNR clears the declared bar (the
    /// nearest-mistake rule, not the bar, catches it there).
    #[test]
    fn a_declared_accuracy_excuses_approximation_not_convention_mistakes() {
        let (mesh, optics, cases) = scene();
        let declared = DeclaredAccuracy {
            min_psnr_db: LOWEST_DECLARED_DB,
            reason: "test noise".into(),
        };
        let mut caught_above_the_bar = vec![];
        for case in cases.iter().filter(|c| c.name != "empty") {
            let cam = &case.camera;
            let r = reference::render(&mesh, &optics, cam);
            let approx = noisy(&r, 0.1);
            let p = psnr_rgba(&approx, &r);
            assert!(
                (declared.min_psnr_db..PASS_DB).contains(&p),
                "{}: {p}",
                case.name
            );
            assert!(judge(&mesh, &optics, cam, &approx, &r, None, None)
                .1
                .is_err());
            let (_, ok) = judge(&mesh, &optics, cam, &approx, &r, Some(&declared), None);
            assert!(ok.is_ok(), "{}: {ok:?}", case.name);
            for m in mistakes(&mesh, &optics, cam, &r) {
                if m.sub_pixel || psnr_rgba(&m.image, &r) >= PASS_DB {
                    continue;
                }
                let wrong = noisy(&m.image, 0.1);
                let (p, verdict) = judge(&mesh, &optics, cam, &wrong, &r, Some(&declared), None);
                let msg = verdict.expect_err(&format!("{}: {} passed", case.name, m.what));
                if p >= declared.min_psnr_db {
                    assert!(msg.starts_with(&m.what), "{}: {}: {msg}", case.name, m.what);
                    caught_above_the_bar.push(format!("{}: {}", case.name, m.what));
                }
            }
        }
        // Premultiplying twice costs less than 35 dB but more than the noise: the bar alone
        // would pass it.
        assert!(
            caught_above_the_bar
                .iter()
                .any(|m| m.contains("premultiplied twice")),
            "{caught_above_the_bar:#?}"
        );
    }
}
