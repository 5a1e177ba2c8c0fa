//! The splatter's work per frame, derived on the CPU from the same f32 arithmetic as the
//! shaders (the roofline's counters, computed once per view and outside the timed frame):
//!
//! * splat fragments: the pixel centres each voxel's footprint square covers (`splat_cs` in
//!   splat.wgsl), times the slabs that draw that voxel (slab i draws buckets i − r … i + r,
//!   `buckets.rs`);
//! * splats: the (voxel, slab) pairs drawn, the same sum without the areas (the row's `splats`
//!   counts them from the bucket table; the tests check the two agree).
//!
//! A square's pixels are the centres (k + ½) with left/top edge ≤ centre < right/bottom edge
//! (a rasteriser's top-left rule on an axis-aligned rectangle, which the compute pass applies
//! itself). The GPU computes the square's centre in f32 through its own matrix product (fused
//! multiply-adds may round differently), so a centre within a hair of an edge can go either
//! way: [`FragmentCount`] also gives the counts with every edge moved in and out by
//! [`EDGE_MARGIN`], which bound what the GPU yields.

use anyhow::Context;
use rayon::prelude::*;
use render_core::Camera;

use crate::buckets::{depth, SlabGeometry};
use crate::gpu::FrameParams;
use crate::Splat;

/// How far (pixels) an edge may move between this twin and the GPU: f32 round-off of the
/// projection, with a wide margin (it also bounds a rasteriser's sub-pixel snapping, ≤ 1/32
/// pixel at Vulkan's minimum 4 sub-pixel bits, should the splats be drawn as quads again).
pub const EDGE_MARGIN: f64 = 1.0 / 16.0;

/// What one frame's splats cover.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FragmentCount {
    /// (voxel, slab) pairs drawn: one quad each.
    pub splats: u64,
    /// Pixel centres inside the quads, summed over every quad drawn.
    pub fragments: u64,
    /// The same with every edge [`EDGE_MARGIN`] inwards / outwards.
    pub at_least: u64,
    pub at_most: u64,
}

impl std::ops::Add for FragmentCount {
    type Output = FragmentCount;
    fn add(self, o: FragmentCount) -> FragmentCount {
        FragmentCount {
            splats: self.splats + o.splats,
            fragments: self.fragments + o.fragments,
            at_least: self.at_least + o.at_least,
            at_most: self.at_most + o.at_most,
        }
    }
}

/// The per-frame parameters `splat_vs` reads (a view's key for the per-view cache).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadParams {
    pub view_proj: [[f32; 4]; 4],
    pub depth_row: [f32; 4],
    pub viewport: [f32; 2],
    pub focal_px: f32,
    pub perspective: bool,
    pub kernel_radius_world: f32,
}

impl QuadParams {
    pub(crate) fn of(u: &FrameParams) -> QuadParams {
        QuadParams {
            view_proj: u.view_proj,
            depth_row: u.depth_row,
            viewport: u.viewport,
            focal_px: u.focal_px,
            perspective: u.perspective != 0,
            kernel_radius_world: u.kernel_radius_world,
        }
    }

    /// The quad of a voxel in pixels (x0, y0, x1, y1), y down; `None` behind the eye (the
    /// shader moves such a quad off screen).
    pub fn quad(&self, v: [f32; 4]) -> Option<[f32; 4]> {
        let d = depth(self.depth_row, v);
        let m = &self.view_proj;
        // Column-major, as WGSL's mat4x4 · vec4.
        let clip: [f32; 4] =
            std::array::from_fn(|r| m[0][r] * v[0] + m[1][r] * v[1] + m[2][r] * v[2] + m[3][r]);
        if clip[3] <= 0.0 || d <= 0.0 {
            return None;
        }
        let (nx, ny) = (clip[0] / clip[3], clip[1] / clip[3]);
        let ppw = if self.perspective {
            self.focal_px / d
        } else {
            self.focal_px
        };
        let half = self.kernel_radius_world * ppw;
        let [w, h] = self.viewport;
        let (cx, cy) = ((nx + 1.0) * 0.5 * w, (1.0 - ny) * 0.5 * h);
        Some([cx - half, cy - half, cx + half, cy + half])
    }
}

/// Pixel centres k + ½ (0 ≤ k < n) with a − grow ≤ k + ½ < b + grow.
fn centres(a: f32, b: f32, n: f32, grow: f64) -> u64 {
    let n = n as f64;
    let first = (a as f64 - grow - 0.5).ceil().clamp(0.0, n);
    let end = (b as f64 + grow - 0.5).ceil().clamp(0.0, n);
    (end - first).max(0.0) as u64
}

/// Pixel centres of a quad with its edges moved outwards by `grow` (inwards when negative).
pub fn quad_pixels(q: [f32; 4], viewport: [f32; 2], grow: f64) -> u64 {
    centres(q[0], q[2], viewport[0], grow) * centres(q[1], q[3], viewport[1], grow)
}

/// Slabs that draw a voxel of bucket `b`: i in [b − r, b + r] among the `drawn` first slabs.
fn slabs_drawing(b: u32, r: u32, drawn: u32) -> u64 {
    if drawn == 0 {
        return 0;
    }
    let lo = b.saturating_sub(r);
    let hi = (b + r).min(drawn - 1);
    (hi + 1).saturating_sub(lo) as u64
}

/// The splats and fragments of one frame over `voxels` (every brick: bricks share the slab
/// geometry), with slabs 0 … `drawn` − 1 drawn.
pub fn frame_fragments(
    p: &QuadParams,
    geom: &SlabGeometry,
    drawn: u32,
    voxels: &[[f32; 4]],
) -> FragmentCount {
    voxels
        .par_iter()
        .map(|&v| {
            let b = geom.slab_of(depth(p.depth_row, v));
            let slabs = slabs_drawing(b, geom.radius_slabs, drawn);
            let area = |grow| p.quad(v).map_or(0, |q| quad_pixels(q, p.viewport, grow));
            FragmentCount {
                splats: slabs,
                fragments: slabs * area(0.0),
                at_least: slabs * area(-EDGE_MARGIN),
                at_most: slabs * area(EDGE_MARGIN),
            }
        })
        .reduce(FragmentCount::default, |a, b| a + b)
}

/// Pixel centres of the voxels' squares that lie outside `rect` = [x0, y0, x1, y1) (the
/// composite's scissor, which must hold every one of them).
pub fn centres_outside(p: &QuadParams, voxels: &[[f32; 4]], rect: [u32; 4]) -> u64 {
    let [x0, y0, x1, y1] = rect.map(|v| v as f64);
    voxels
        .par_iter()
        .filter_map(|&v| p.quad(v))
        .map(|q| {
            let all = quad_pixels(q, p.viewport, 0.0);
            // Centres inside the rectangle: the same rule on the square clipped to it.
            let clip = |a: f32, lo: f64, hi: f64| (a as f64).clamp(lo, hi) as f32;
            let inside = quad_pixels(
                [
                    clip(q[0], x0, x1),
                    clip(q[1], y0, y1),
                    clip(q[2], x0, x1),
                    clip(q[3], y0, y1),
                ],
                p.viewport,
                0.0,
            );
            all - inside
        })
        .sum()
}

impl Splat {
    /// Test hook: early splat elimination drops (and counts) every splat fragment, so the
    /// row's `ese_dropped_fragments` is the GPU's count of the fragments `splat_fragments`
    /// derives.
    #[doc(hidden)]
    pub fn counting_every_fragment(mut self) -> Splat {
        self.count_every_fragment = true;
        self
    }

    /// Each slab splats buckets i − r … i + r into its own sheet, the paper's order (§3.6),
    /// instead of each bucket once into the ring of sheets: the twin the ring must equal bit
    /// for bit.
    #[doc(hidden)]
    pub fn slab_by_slab(mut self) -> Splat {
        self.slab_by_slab = true;
        self
    }

    /// Splits each voxel's footprint over `lanes` invocations on any adapter (the split a GPU
    /// gets, `Splat::lanes`): the image must not change by a bit.
    #[doc(hidden)]
    pub fn with_lanes(mut self, lanes: u32) -> Splat {
        self.forced_lanes = Some(lanes);
        self
    }

    /// The footprint table loaded and interpolated by hand (the path of devices that cannot
    /// filter `R32Float`) instead of sampled with trilinear filtering.
    #[doc(hidden)]
    pub fn with_table_loads(mut self) -> Splat {
        self.table_loads = true;
        self
    }

    /// Footprint pixel centres of `camera`'s view outside `rect` (see [`centres_outside`]).
    #[doc(hidden)]
    pub fn centres_outside(&self, camera: &Camera, rect: [u32; 4]) -> anyhow::Result<u64> {
        let st = self.state.as_ref().context("splat: prepare first")?;
        let geom = self.geometry(st, camera);
        let quad = QuadParams::of(&self.frame_params(camera, &geom, 0));
        Ok(centres_outside(&quad, &st.set.voxels, rect))
    }

    /// The splat coverage of `camera`'s view (derived on the CPU, cached per view), and its
    /// bounds ([`FragmentCount`]).
    pub fn fragment_count(&mut self, camera: &Camera) -> anyhow::Result<FragmentCount> {
        let st = self.state.as_ref().context("splat: prepare first")?;
        let geom = self.geometry(st, camera);
        let quad = QuadParams::of(&self.frame_params(camera, &geom, 0));
        if let Some((q, g, c)) = &self.coverage {
            if *q == quad && *g == geom {
                return Ok(*c);
            }
        }
        let drawn = geom.num_slabs.min(st.max_slabs);
        let c = frame_fragments(&quad, &geom, drawn, &st.set.voxels);
        self.coverage = Some((quad, geom, c));
        Ok(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quad_covers_the_centres_inside_its_left_and_top_edges() {
        // [2, 5) × [1, 3.5): centres 2.5, 3.5, 4.5 across, 1.5, 2.5 down.
        assert_eq!(quad_pixels([2.0, 1.0, 5.0, 3.5], [16.0, 16.0], 0.0), 6);
        // A left edge on a centre includes it, a right edge on a centre excludes it.
        assert_eq!(quad_pixels([2.5, 0.0, 4.5, 1.0], [16.0, 16.0], 0.0), 2);
        // Clipped to the viewport.
        assert_eq!(quad_pixels([-3.0, -3.0, 2.0, 2.0], [16.0, 16.0], 0.0), 4);
        assert_eq!(quad_pixels([15.2, 0.0, 19.0, 1.0], [16.0, 16.0], 0.0), 1);
        assert_eq!(quad_pixels([20.0, 0.0, 29.0, 1.0], [16.0, 16.0], 0.0), 0);
        // The margins bracket a centre on an edge.
        let q = [2.5, 0.2, 4.5, 0.8];
        assert_eq!(quad_pixels(q, [16.0, 16.0], -EDGE_MARGIN), 1);
        assert_eq!(quad_pixels(q, [16.0, 16.0], EDGE_MARGIN), 3);
    }

    #[test]
    fn a_voxel_is_drawn_by_the_slabs_within_the_kernel_radius() {
        assert_eq!(slabs_drawing(5, 2, 20), 5);
        assert_eq!(slabs_drawing(0, 2, 20), 3);
        assert_eq!(slabs_drawing(19, 2, 20), 3);
        assert_eq!(slabs_drawing(1, 0, 20), 1);
        assert_eq!(slabs_drawing(3, 2, 0), 0);
    }

    /// An orthographic camera looking down −z at 10 pixels per unit: a voxel at the origin
    /// with kernel radius 0.25 is a 5 × 5 pixel quad centred on the viewport's centre.
    #[test]
    fn an_orthographic_quad_has_the_kernel_radius_in_pixels() {
        let p = QuadParams {
            // x and y to NDC over a 32 × 32 viewport at 10 px per unit: 1 unit = 10/16 NDC.
            view_proj: [
                [0.625, 0.0, 0.0, 0.0],
                [0.0, 0.625, 0.0, 0.0],
                [0.0, 0.0, -0.1, 0.0],
                [0.0, 0.0, 0.5, 1.0],
            ],
            depth_row: [0.0, 0.0, 1.0, -5.0],
            viewport: [32.0, 32.0],
            focal_px: 10.0,
            perspective: false,
            kernel_radius_world: 0.25,
        };
        let q = p.quad([0.0, 0.0, 0.0, 1.0]).unwrap();
        assert_eq!(q, [13.5, 13.5, 18.5, 18.5]);
        // Edges on centres: left/top in, right/bottom out.
        assert_eq!(quad_pixels(q, p.viewport, 0.0), 25);
        assert_eq!(quad_pixels(q, p.viewport, -EDGE_MARGIN), 16);
        assert_eq!(quad_pixels(q, p.viewport, EDGE_MARGIN), 36);
        // Behind the eye: not drawn.
        assert_eq!(p.quad([0.0, 0.0, 10.0, 1.0]), None);
        let geom = SlabGeometry::new(4.0, 6.0, 0.5, 0.5, 1);
        let c = frame_fragments(&p, &geom, geom.num_slabs, &[[0.0, 0.0, 0.0, 1.0]]);
        assert_eq!((c.splats, c.fragments), (3, 75));
    }
}
