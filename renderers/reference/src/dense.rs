//! Dense sampling: an independent brute-force integrator (point location at small steps), used
//! only to test the exact walk of [`crate::Prepared`].

use datasets::TetMesh;
use glam::DVec3;
use rayon::prelude::*;
use render_core::preintegration::composite_front_to_back;
use render_core::{Camera, Image, Optics};

use crate::OPAQUE;

/// A uniform grid over the mesh bounds listing the tets whose boxes overlap each cell.
struct Locator<'m> {
    mesh: &'m TetMesh,
    min: DVec3,
    cell: DVec3,
    dims: [usize; 3],
    offsets: Vec<u32>,
    tets: Vec<u32>,
}

impl<'m> Locator<'m> {
    fn new(mesh: &'m TetMesh) -> Locator<'m> {
        let b = mesh.bounds();
        let min = DVec3::from(b.min);
        let ext = DVec3::from(b.extent()).max(DVec3::splat(1e-30));
        let n = (mesh.num_tets() as f64).cbrt().ceil().max(1.0);
        let longest = ext.max_element();
        let dims = [0, 1, 2].map(|a| ((ext[a] / longest * n).ceil() as usize).clamp(1, 256));
        let cell = DVec3::new(
            ext.x / dims[0] as f64,
            ext.y / dims[1] as f64,
            ext.z / dims[2] as f64,
        );
        let ncell = dims[0] * dims[1] * dims[2];
        let range = |t: usize| {
            let p = mesh.tet_points(t).map(DVec3::from);
            let lo = p[0].min(p[1]).min(p[2]).min(p[3]);
            let hi = p[0].max(p[1]).max(p[2]).max(p[3]);
            let c = |x: DVec3| {
                [0, 1, 2].map(|a| {
                    (((x[a] - min[a]) / cell[a]).floor().max(0.0) as usize).min(dims[a] - 1)
                })
            };
            (c(lo), c(hi))
        };
        let mut counts = vec![0u32; ncell + 1];
        for t in 0..mesh.num_tets() {
            let (lo, hi) = range(t);
            for k in lo[2]..=hi[2] {
                for j in lo[1]..=hi[1] {
                    for i in lo[0]..=hi[0] {
                        counts[i + dims[0] * (j + dims[1] * k) + 1] += 1;
                    }
                }
            }
        }
        for i in 1..counts.len() {
            counts[i] += counts[i - 1];
        }
        let mut fill = counts.clone();
        let mut tets = vec![0u32; counts[ncell] as usize];
        for t in 0..mesh.num_tets() {
            let (lo, hi) = range(t);
            for k in lo[2]..=hi[2] {
                for j in lo[1]..=hi[1] {
                    for i in lo[0]..=hi[0] {
                        let c = i + dims[0] * (j + dims[1] * k);
                        tets[fill[c] as usize] = t as u32;
                        fill[c] += 1;
                    }
                }
            }
        }
        Locator {
            mesh,
            min,
            cell,
            dims,
            offsets: counts,
            tets,
        }
    }

    /// The interpolated scalar at `x`, or `None` outside the mesh (barycentric coordinates by
    /// Cramer's rule, tolerance 1e-12).
    fn scalar_at(&self, x: DVec3) -> Option<f64> {
        let mut c = [0usize; 3];
        for a in 0..3 {
            let f = (x[a] - self.min[a]) / self.cell[a];
            if !(f >= -1e-9 && f <= self.dims[a] as f64 + 1e-9) {
                return None;
            }
            c[a] = (f.floor().max(0.0) as usize).min(self.dims[a] - 1);
        }
        let cell = c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2]);
        for &t in &self.tets[self.offsets[cell] as usize..self.offsets[cell + 1] as usize] {
            let p = self.mesh.tet_points(t as usize).map(DVec3::from);
            let (e1, e2, e3, r) = (p[1] - p[0], p[2] - p[0], p[3] - p[0], x - p[0]);
            let det = e1.dot(e2.cross(e3));
            let l1 = r.dot(e2.cross(e3)) / det;
            let l2 = e1.dot(r.cross(e3)) / det;
            let l3 = e1.dot(e2.cross(r)) / det;
            let l0 = 1.0 - l1 - l2 - l3;
            let tol = -1e-12;
            if l0 >= tol && l1 >= tol && l2 >= tol && l3 >= tol {
                let s = self.mesh.tets[t as usize].map(|v| self.mesh.scalars[v as usize] as f64);
                return Some(l0 * s[0] + l1 * s[1] + l2 * s[2] + l3 * s[3]);
            }
        }
        None
    }
}

/// Brute-force integration for tests: each pixel ray is marched in steps of `step_world`
/// through the mesh's bounding box; the scalar is found by point location at each step's
/// midpoint and the ray equation integrated with the midpoint rule (per step, opacity
/// 1 − exp(−κ·h) and colour c·opacity). Where a step enters or leaves the mesh the crossing is
/// found by bisection, so the boundary costs no first-order error; steps that start and end
/// outside are probed at eighths for thin corners of the mesh. Error O(step²).
pub fn dense_sampling(mesh: &TetMesh, optics: &Optics, camera: &Camera, step_world: f64) -> Image {
    let loc = Locator::new(mesh);
    let b = mesh.bounds();
    let pad = 1e-9 * b.diagonal();
    let (bmin, bmax) = (DVec3::from(b.min) - pad, DVec3::from(b.max) + pad);
    let (w, h) = (camera.width, camera.height);
    let mut pixels = vec![[0f32; 4]; (w * h) as usize];
    pixels.par_iter_mut().enumerate().for_each(|(i, px)| {
        let ray = camera.pixel_ray(i as u32 % w, i as u32 / w);
        let (o, d) = (DVec3::from(ray.origin), DVec3::from(ray.dir));
        // Slab test against the bounding box.
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for a in 0..3 {
            if d[a].abs() < 1e-300 {
                if o[a] < bmin[a] || o[a] > bmax[a] {
                    return;
                }
                continue;
            }
            let (ta, tb) = ((bmin[a] - o[a]) / d[a], (bmax[a] - o[a]) / d[a]);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        if !(t1 > t0) {
            return;
        }
        let at = |t: f64| loc.scalar_at(o + d * t);
        let inside = |t: f64| at(t).is_some();
        let mut acc = [0.0f64; 4];
        let add = |ta: f64, tb: f64, acc: &mut [f64; 4]| {
            if let Some(s) = at(0.5 * (ta + tb)) {
                let s = optics.normalise(s);
                let a = 1.0 - (-optics.tf.kappa_at(s) * (tb - ta) / optics.length_unit).exp();
                let c = optics.tf.color_at(s);
                composite_front_to_back(acc, [c[0] * a, c[1] * a, c[2] * a, a]);
            }
        };
        let crossing = |mut lo: f64, mut hi: f64, lo_inside: bool| {
            for _ in 0..60 {
                let m = 0.5 * (lo + hi);
                if inside(m) == lo_inside {
                    lo = m;
                } else {
                    hi = m;
                }
            }
            0.5 * (lo + hi)
        };
        let n = ((t1 - t0) / step_world).ceil().max(1.0) as usize;
        let hstep = (t1 - t0) / n as f64;
        let mut prev_in = inside(t0);
        for k in 0..n {
            let (ta, tb) = (t0 + k as f64 * hstep, t0 + (k + 1) as f64 * hstep);
            let next_in = inside(tb);
            match (prev_in, next_in) {
                (true, true) => add(ta, tb, &mut acc),
                (false, false) => {
                    // A corner of the mesh thinner than a step: probe inside the step, so
                    // pieces longer than an eighth of a step are not missed.
                    if let Some(m) = (1..8)
                        .map(|q| ta + q as f64 * hstep / 8.0)
                        .find(|&t| inside(t))
                    {
                        let (c0, c1) = (crossing(ta, m, false), crossing(m, tb, true));
                        add(c0, c1, &mut acc);
                    }
                }
                (true, false) => {
                    let tc = crossing(ta, tb, true);
                    add(ta, tc, &mut acc);
                }
                (false, true) => {
                    let tc = crossing(ta, tb, false);
                    add(tc, tb, &mut acc);
                }
            }
            prev_in = next_in;
            if acc[3] > OPAQUE {
                break;
            }
        }
        *px = acc.map(|v| v as f32);
    });
    Image {
        width: w,
        height: h,
        pixels,
    }
}
