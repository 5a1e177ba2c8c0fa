//! How tetbench's scene maps onto VTK's, in one place (the README's conventions table is this
//! module in words). Every function here is pure, so the tests check the mapping without VTK.
//!
//! * Extinction: tetbench's κ(s) is per unit of the bounding-box diagonal; VTK's unstructured
//!   integrators (and its PT and ZSweep mappers) attenuate by `opacity / ScalarOpacityUnitDistance`
//!   per world unit. With K = max κ, opacity = κ/K and unit distance = diagonal/K give the same
//!   attenuation κ/diagonal per world unit, with opacities inside [0, 1].
//! * Control points: VTK's linear and partial pre-integration integrators split a ray segment
//!   only at the opacity function's points, so colour and opacity get one shared set of points
//!   (every breakpoint of either tetbench function), each carrying both values there. Between
//!   them both functions are linear, so VTK's functions equal tetbench's everywhere.
//! * Colour: RGB interpolation over the raw scalar x = lo + s·(hi − lo), s the normalised scalar.
//! * Camera: same eye, focal point, up, vertical view angle (or parallel scale) and clipping
//!   range. VTK's ray caster samples pixel X at NDC 2X/W − 1, half a pixel off tetbench's pixel
//!   centres; a window centre of (1/W, 1/H) moves its rays onto the centres.

use render_core::{Camera, Optics, Projection};
use serde_json::{json, Value};

/// The transfer function as VTK's functions take it.
#[derive(Debug, Clone, PartialEq)]
pub struct VtkTransfer {
    /// `[x, r, g, b, opacity]` at every breakpoint, x in the mesh's scalar units, sorted.
    pub points: Vec<[f64; 5]>,
    /// `vtkVolumeProperty::ScalarOpacityUnitDistance`, world units.
    pub unit_distance: f64,
}

/// Maps `optics` onto shared colour/opacity points and a unit distance (see the module doc).
pub fn vtk_transfer(optics: &Optics) -> VtkTransfer {
    let tf = &optics.tf;
    let k = tf.max_kappa();
    let k = if k > 0.0 { k } else { 1.0 };
    let mut s_points = tf.breakpoints();
    // Clamped ends: both functions are constant outside [0, 1].
    s_points.retain(|s| (0.0..=1.0).contains(s));
    for end in [0.0, 1.0] {
        if !s_points.contains(&end) {
            s_points.push(end);
        }
    }
    s_points.sort_by(f64::total_cmp);
    let span = optics.scalar_max - optics.scalar_min;
    let points = s_points
        .iter()
        .map(|&s| {
            let c = tf.color_at(s);
            [
                optics.scalar_min + s * span,
                c[0],
                c[1],
                c[2],
                tf.kappa_at(s) / k,
            ]
        })
        .collect();
    VtkTransfer {
        points,
        unit_distance: optics.length_unit / k,
    }
}

/// Where VTK's rays or rasteriser sample a pixel, and how the camera is adjusted for it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelSampling {
    /// Rasterisers (OpenGL): pixel centres already; the camera is passed as it is.
    Centres,
    /// VTK's ray caster (Bunyk): pixel corners; shifted by a window centre of (1/W, 1/H).
    Corners,
}

/// The camera request of the peer protocol; `nudge_deg` turns the eye about the up axis
/// (VTK's `Azimuth`) so that each timed frame is a new view.
pub fn camera_request(camera: &Camera, sampling: PixelSampling) -> Value {
    let (w, h) = (camera.width as f64, camera.height as f64);
    let window_center = match sampling {
        PixelSampling::Centres => [0.0, 0.0],
        PixelSampling::Corners => [1.0 / w, 1.0 / h],
    };
    let (view_angle, parallel_scale) = match camera.projection {
        Projection::Perspective { fovy_deg } => (fovy_deg, None),
        Projection::Orthographic => (30.0, Some(camera.ortho_half_height)),
    };
    json!({
        "eye": camera.eye,
        "focal": camera.target,
        "up": camera.up,
        "view_angle": view_angle,
        "parallel_scale": parallel_scale,
        "window_center": window_center,
        "near": camera.near,
        "far": camera.far,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use render_core::transfer::{ColorPoint, KappaPoint};
    use render_core::TransferFunction;

    fn optics(tf: TransferFunction) -> Optics {
        Optics {
            tf,
            scalar_min: -2.0,
            scalar_max: 6.0,
            length_unit: 10.0,
        }
    }

    /// VTK's attenuation per world unit (opacity / unit distance, linear between the shared
    /// points) equals κ(s)/diagonal, and its colour equals c(s), at every s.
    #[test]
    fn shared_points_reproduce_both_functions() {
        let tf = TransferFunction {
            name: "t".into(),
            color: vec![
                ColorPoint {
                    s: 0.0,
                    rgb: [1.0, 0.0, 0.0],
                },
                ColorPoint {
                    s: 0.3,
                    rgb: [0.0, 1.0, 0.0],
                },
                ColorPoint {
                    s: 1.0,
                    rgb: [0.0, 0.0, 1.0],
                },
            ],
            kappa: vec![
                KappaPoint { s: 0.1, kappa: 2.0 },
                KappaPoint { s: 0.8, kappa: 8.0 },
            ],
        };
        let o = optics(tf.clone());
        let v = vtk_transfer(&o);
        let xs: Vec<f64> = v.points.iter().map(|p| p[0]).collect();
        // s = 0, 0.1, 0.3, 0.8, 1 in scalar units.
        let want = [-2.0, -1.2, 0.4, 4.4, 6.0];
        assert_eq!(xs.len(), want.len());
        for (x, w) in xs.iter().zip(want) {
            assert!((x - w).abs() < 1e-12, "{xs:?}");
        }
        assert!(v.points.iter().all(|p| (0.0..=1.0).contains(&p[4])));
        for i in 0..=200 {
            let s = i as f64 / 200.0;
            let x = -2.0 + 8.0 * s;
            let j = v
                .points
                .partition_point(|p| p[0] <= x)
                .clamp(1, v.points.len() - 1);
            let (a, b) = (v.points[j - 1], v.points[j]);
            let t = ((x - a[0]) / (b[0] - a[0])).clamp(0.0, 1.0);
            let lerp = |k: usize| a[k] + t * (b[k] - a[k]);
            let tau = lerp(4) / v.unit_distance;
            assert!((tau - tf.kappa_at(s) / 10.0).abs() < 1e-12, "s={s}");
            let c = tf.color_at(s);
            for (k, ck) in c.iter().enumerate() {
                assert!((lerp(k + 1) - ck).abs() < 1e-12, "s={s}");
            }
        }
    }

    #[test]
    fn zero_extinction_keeps_a_finite_unit_distance() {
        let mut tf = TransferFunction::preset("low-opacity").unwrap();
        for p in &mut tf.kappa {
            p.kappa = 0.0;
        }
        let v = vtk_transfer(&optics(tf));
        assert_eq!(v.unit_distance, 10.0);
        assert!(v.points.iter().all(|p| p[4] == 0.0));
    }

    #[test]
    fn ray_caster_camera_is_shifted_half_a_pixel() {
        let b = datasets::Aabb {
            min: [0.0; 3],
            max: [1.0; 3],
        };
        let vp = render_core::fixed_viewpoints()[6].clone();
        let cam = Camera::fit(&b, &vp, Projection::default(), 128, 64);
        let r = camera_request(&cam, PixelSampling::Corners);
        assert_eq!(r["window_center"], json!([1.0 / 128.0, 1.0 / 64.0]));
        assert_eq!(r["view_angle"], json!(30.0));
        assert!(r["parallel_scale"].is_null());
        let r = camera_request(&cam, PixelSampling::Centres);
        assert_eq!(r["window_center"], json!([0.0, 0.0]));
    }
    /// A ParaView colormap with opacities renders in VTK with ParaView's own attenuation:
    /// opacity o at x attenuates o / u per world unit, u = diagonal / PARAVIEW_OPACITY_SCALE.
    #[test]
    fn paraview_colormap_maps_back_to_paraview_attenuation() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("pv.json");
        std::fs::write(
            &path,
            r#"[{"Name":"ramp","RGBPoints":[10,0,0,1, 30,1,0,0],"Points":[10,0.1,0.5,0, 20,0.8,0.5,0, 30,0.4,0.5,0]}]"#,
        )
        .unwrap();
        let tf = TransferFunction::load(path.to_str().unwrap()).unwrap();
        let optics = Optics {
            tf,
            scalar_min: 10.0,
            scalar_max: 30.0,
            length_unit: 7.0,
        };
        let v = vtk_transfer(&optics);
        let u = 7.0 / render_core::transfer::PARAVIEW_OPACITY_SCALE;
        let want = [(10.0, 0.1), (20.0, 0.8), (30.0, 0.4)];
        assert_eq!(v.points.len(), want.len());
        for (p, (x, o)) in v.points.iter().zip(want) {
            assert!((p[0] - x).abs() < 1e-12);
            assert!((p[4] / v.unit_distance - o / u).abs() < 1e-9, "{p:?}");
        }
    }
}
