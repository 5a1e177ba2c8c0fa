//! Cameras and the fixed viewpoints of the papers' tables.
//!
//! Conventions shared by every renderer and the reference: right-handed world, camera looks
//! down −z in view space, clip-space depth in [0, 1] (wgpu), pixel (x, y) has its centre at
//! (x + ½, y + ½) with row 0 at the top of the image.

use datasets::Aabb;
use glam::{DMat4, DVec3, DVec4, Mat4};
use serde::{Deserialize, Serialize};

/// Perspective or orthographic projection.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Projection {
    /// Vertical field of view in degrees (30° by default, as for the HAVS tables).
    Perspective {
        fovy_deg: f64,
    },
    Orthographic,
}

impl Default for Projection {
    fn default() -> Self {
        Projection::Perspective { fovy_deg: 30.0 }
    }
}

/// A named direction from which the mesh is viewed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Viewpoint {
    /// e.g. `+x`, `-y`, `+x+y-z`, `orbit03of36`.
    pub name: String,
    /// Unit vector from the mesh centre towards the eye.
    pub direction: [f64; 3],
}

impl Viewpoint {
    pub fn new(name: impl Into<String>, direction: [f64; 3]) -> Viewpoint {
        let d = DVec3::from(direction).normalize();
        Viewpoint {
            name: name.into(),
            direction: d.into(),
        }
    }
}

/// The 14 viewpoints of the HAVS tables: the 6 axis directions, then the 8 cube diagonals.
pub fn fixed_viewpoints() -> Vec<Viewpoint> {
    let mut v = Vec::with_capacity(14);
    for (axis, name) in [(0usize, 'x'), (1, 'y'), (2, 'z')] {
        for sign in [1.0, -1.0] {
            let mut d = [0.0; 3];
            d[axis] = sign;
            v.push(Viewpoint::new(
                format!("{}{name}", if sign > 0.0 { '+' } else { '-' }),
                d,
            ));
        }
    }
    for sx in [1.0, -1.0] {
        for sy in [1.0, -1.0] {
            for sz in [1.0, -1.0] {
                let s = |x: f64| if x > 0.0 { '+' } else { '-' };
                v.push(Viewpoint::new(
                    format!("{}x{}y{}z", s(sx), s(sy), s(sz)),
                    [sx, sy, sz],
                ));
            }
        }
    }
    v
}

/// `n` frames of a full turn about the up (+y) axis, slightly from above, as the PT papers time
/// a "constantly rotating" model.
pub fn orbit_viewpoints(n: usize) -> Vec<Viewpoint> {
    let elevation = 20f64.to_radians();
    (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            let d = [
                elevation.cos() * a.sin(),
                elevation.sin(),
                elevation.cos() * a.cos(),
            ];
            Viewpoint::new(format!("orbit{:03}of{n}", i), d)
        })
        .collect()
}

/// A camera fitted to a mesh: view and projection in f64, with the f32 matrices shaders need.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    pub eye: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    pub projection: Projection,
    /// Half the visible height at the target distance (orthographic), or unused.
    pub ortho_half_height: f64,
    pub near: f64,
    pub far: f64,
    pub width: u32,
    pub height: u32,
    pub viewpoint: String,
}

/// A ray in world space; `dir` is unit length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub origin: [f64; 3],
    pub dir: [f64; 3],
}

impl Camera {
    /// Fits the mesh's bounding sphere into the view from `viewpoint`.
    pub fn fit(
        bounds: &Aabb,
        viewpoint: &Viewpoint,
        projection: Projection,
        width: u32,
        height: u32,
    ) -> Camera {
        let center = DVec3::from(bounds.center());
        let radius = 0.5 * bounds.diagonal().max(1e-30);
        let dir = DVec3::from(viewpoint.direction).normalize();
        let aspect = width as f64 / height as f64;
        let (distance, half_height) = match projection {
            Projection::Perspective { fovy_deg } => {
                // The sphere must fit the narrower of the two fields of view.
                let half_v = (fovy_deg.to_radians() * 0.5).min(1.5);
                let half_h = (half_v.tan() * aspect).atan();
                let half = half_v.min(half_h);
                (radius / half.sin(), 0.0)
            }
            Projection::Orthographic => (2.0 * radius, radius * (1.0f64).max(1.0 / aspect)),
        };
        let eye = center + dir * distance;
        let up = if dir.y.abs() > 0.99 {
            DVec3::Z
        } else {
            DVec3::Y
        };
        Camera {
            eye: eye.into(),
            target: center.into(),
            up: up.into(),
            projection,
            ortho_half_height: half_height,
            near: (distance - radius * 1.01).max(distance * 1e-3),
            far: distance + radius * 1.01,
            width,
            height,
            viewpoint: viewpoint.name.clone(),
        }
    }

    pub fn view(&self) -> DMat4 {
        DMat4::look_at_rh(self.eye.into(), self.target.into(), self.up.into())
    }

    pub fn proj(&self) -> DMat4 {
        let aspect = self.width as f64 / self.height as f64;
        match self.projection {
            Projection::Perspective { fovy_deg } => {
                DMat4::perspective_rh(fovy_deg.to_radians(), aspect, self.near, self.far)
            }
            Projection::Orthographic => {
                let h = self.ortho_half_height;
                DMat4::orthographic_rh(-h * aspect, h * aspect, -h, h, self.near, self.far)
            }
        }
    }

    pub fn view_proj(&self) -> DMat4 {
        self.proj() * self.view()
    }

    /// Column-major view-projection for WGSL uniforms.
    pub fn view_proj_f32(&self) -> [[f32; 4]; 4] {
        let m: Mat4 = self.view_proj().as_mat4();
        m.to_cols_array_2d()
    }

    /// Column-major view matrix for WGSL uniforms.
    pub fn view_f32(&self) -> [[f32; 4]; 4] {
        self.view().as_mat4().to_cols_array_2d()
    }

    /// Tets with a vertex at or behind the eye plane (clip w ≤ 0 with the f32 matrix the
    /// shaders use): projected-tetrahedra algorithms cannot draw them (GATOR drops them, the
    /// fragment PT projection is undefined for them), so rows count them (`tets_behind_eye`).
    pub fn tets_behind_eye(&self, mesh: &datasets::TetMesh) -> u64 {
        use rayon::prelude::*;
        if !self.is_perspective() {
            return 0;
        }
        let m = self.view_proj_f32();
        let behind: Vec<bool> = mesh
            .points
            .par_iter()
            .map(|p| m[0][3] * p[0] + m[1][3] * p[1] + m[2][3] * p[2] + m[3][3] <= 0.0)
            .collect();
        mesh.tets
            .par_iter()
            .filter(|t| t.iter().any(|&v| behind[v as usize]))
            .count() as u64
    }

    pub fn is_perspective(&self) -> bool {
        matches!(self.projection, Projection::Perspective { .. })
    }

    /// Unit vector along which the camera looks.
    pub fn forward(&self) -> [f64; 3] {
        (DVec3::from(self.target) - DVec3::from(self.eye))
            .normalize()
            .into()
    }

    /// The ray through the image point (`px`, `py`) in pixels (pixel centres at +½).
    pub fn ray(&self, px: f64, py: f64) -> Ray {
        let ndc_x = px / self.width as f64 * 2.0 - 1.0;
        let ndc_y = 1.0 - py / self.height as f64 * 2.0;
        let inv = self.view_proj().inverse();
        let unproject = |z: f64| {
            let p = inv * DVec4::new(ndc_x, ndc_y, z, 1.0);
            p.truncate() / p.w
        };
        let a = unproject(0.0);
        let b = unproject(1.0);
        let dir = (b - a).normalize();
        let origin = if self.is_perspective() {
            DVec3::from(self.eye)
        } else {
            a
        };
        Ray {
            origin: origin.into(),
            dir: dir.into(),
        }
    }

    /// The ray through the centre of pixel (`x`, `y`).
    pub fn pixel_ray(&self, x: u32, y: u32) -> Ray {
        self.ray(x as f64 + 0.5, y as f64 + 0.5)
    }

    /// Visibility-sort key of a point: distance from the eye for perspective (HAVS §5.1 sorts
    /// face centroids by distance to the viewpoint), depth along the view axis otherwise.
    /// Larger is farther.
    pub fn sort_distance(&self, p: [f64; 3]) -> f64 {
        let d = DVec3::from(p) - DVec3::from(self.eye);
        if self.is_perspective() {
            d.length()
        } else {
            d.dot(DVec3::from(self.forward()))
        }
    }

    /// The pixel rectangle `[x0, x1) × [y0, y1)` that holds every pixel centre the box can
    /// cover (its eight corners projected, widened by a pixel); the whole viewport when a corner
    /// lies at or behind the eye plane, where the projection of the box is unbounded. Renderers
    /// with per-pixel passes use it to leave alone the pixels no fragment can reach.
    pub fn covered_rect(&self, bounds: &Aabb) -> [u32; 4] {
        let full = [0, 0, self.width, self.height];
        let vp = self.view_proj();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for corner in 0..8 {
            let pick = |axis: usize| {
                if corner >> axis & 1 == 1 {
                    bounds.max[axis]
                } else {
                    bounds.min[axis]
                }
            };
            let c = vp * DVec4::new(pick(0), pick(1), pick(2), 1.0);
            if c.w <= 1e-9 * c.truncate().length().max(1.0) {
                return full;
            }
            let x = (c.x / c.w + 1.0) * 0.5 * self.width as f64;
            let y = (1.0 - c.y / c.w) * 0.5 * self.height as f64;
            lo = [lo[0].min(x), lo[1].min(y)];
            hi = [hi[0].max(x), hi[1].max(y)];
        }
        let clamp = |v: f64, n: u32| v.clamp(0.0, n as f64) as u32;
        [
            clamp(lo[0].floor() - 1.0, self.width),
            clamp(lo[1].floor() - 1.0, self.height),
            clamp(hi[0].ceil() + 1.0, self.width),
            clamp(hi[1].ceil() + 1.0, self.height),
        ]
    }

    /// Projects a world point to pixel coordinates (x right, y down) and view depth.
    pub fn project_to_pixel(&self, p: [f64; 3]) -> [f64; 3] {
        let c = self.view_proj() * DVec4::new(p[0], p[1], p[2], 1.0);
        let ndc = c.truncate() / c.w;
        [
            (ndc.x + 1.0) * 0.5 * self.width as f64,
            (1.0 - ndc.y) * 0.5 * self.height as f64,
            ndc.z,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn covered_rect_holds_every_projected_point_and_falls_back_behind_the_eye() {
        let b = Aabb {
            min: [-1.0, -0.5, -0.25],
            max: [1.0, 0.5, 0.25],
        };
        for vp in fixed_viewpoints() {
            let cam = Camera::fit(&b, &vp, Projection::default(), 200, 120);
            let [x0, y0, x1, y1] = cam.covered_rect(&b);
            assert!(x0 < x1 && y0 < y1 && x1 <= 200 && y1 <= 120, "{vp:?}");
            // Points inside the box land inside the rectangle.
            for i in 0..=4 {
                for j in 0..=4 {
                    for k in 0..=4 {
                        let f =
                            |t: usize, a: usize| b.min[a] + (b.max[a] - b.min[a]) * t as f64 / 4.0;
                        let [x, y, _] = cam.project_to_pixel([f(i, 0), f(j, 1), f(k, 2)]);
                        assert!(x >= x0 as f64 && x <= x1 as f64, "{vp:?} x {x}");
                        assert!(y >= y0 as f64 && y <= y1 as f64, "{vp:?} y {y}");
                    }
                }
            }
        }
        // An eye inside the box: the whole viewport.
        let mut cam = Camera::fit(&b, &fixed_viewpoints()[0], Projection::default(), 64, 48);
        cam.eye = [0.5, 0.1, 0.05];
        assert_eq!(cam.covered_rect(&b), [0, 0, 64, 48]);
    }

    #[test]
    fn fourteen_distinct_viewpoints() {
        let v = fixed_viewpoints();
        assert_eq!(v.len(), 14);
        let mut names: Vec<_> = v.iter().map(|v| v.name.clone()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), 14);
    }

    #[test]
    fn centre_pixel_ray_hits_target_and_projection_inverts() {
        let b = Aabb {
            min: [-1.0, -2.0, 0.0],
            max: [3.0, 1.0, 2.0],
        };
        for vp in fixed_viewpoints() {
            for proj in [Projection::default(), Projection::Orthographic] {
                let cam = Camera::fit(&b, &vp, proj, 64, 48);
                let r = cam.ray(32.0, 24.0);
                let to_t = DVec3::from(cam.target) - DVec3::from(r.origin);
                let off = to_t - DVec3::from(r.dir) * to_t.dot(DVec3::from(r.dir));
                assert!(off.length() < 1e-9, "{}", vp.name);
                let px = cam.project_to_pixel([2.0, 0.5, 1.5]);
                let r = cam.ray(px[0], px[1]);
                let to_p = DVec3::new(2.0, 0.5, 1.5) - DVec3::from(r.origin);
                let off = to_p - DVec3::from(r.dir) * to_p.dot(DVec3::from(r.dir));
                assert!(off.length() < 1e-9);
                // Every bounding-box corner is inside the view.
                for c in 0..8 {
                    let p = [0, 1, 2].map(|a| if c >> a & 1 == 1 { b.max[a] } else { b.min[a] });
                    let q = cam.project_to_pixel(p);
                    assert!(
                        q[0] >= 0.0
                            && q[0] <= 64.0
                            && q[1] >= 0.0
                            && q[1] <= 48.0
                            && q[2] > 0.0
                            && q[2] < 1.0
                    );
                }
            }
        }
    }
}
