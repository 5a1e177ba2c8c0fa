//! The voxels a frame splats: the grid (the mesh's own, or the mesh resampled), the relevant
//! ("effective") voxels under the transfer function (Grau & Tost §2: voxels of zero opacity
//! are never splatted; the selection is done once per transfer function and kept as a list
//! sorted by value), and their bricks (§4: when the selection exceeds one texture — here one
//! storage binding — the volume is split into octants, each brick drawn on its own in
//! camera order).

use datasets::{GridValues, TetMesh, VoxelGrid, VoxelVolume};
use rayon::prelude::*;
use render_core::Optics;

/// One brick: a box of grid indices and its voxels (a range of [`VoxelSet::voxels`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Brick {
    pub lo: [usize; 3],
    pub hi: [usize; 3],
    pub range: std::ops::Range<usize>,
}

/// The octree over bricks, for front-to-back brick order.
#[derive(Debug, Clone, PartialEq)]
enum Node {
    Leaf(usize),
    /// Split at grid index `mid` per axis (low half `< mid`); children indexed x + 2y + 4z.
    Split {
        mid: [usize; 3],
        children: Vec<Option<Node>>,
    },
}

/// Everything the GPU needs about the voxels, independent of the view.
#[derive(Debug, Clone)]
pub struct VoxelSet {
    /// World position and normalised value (s ∈ [0, 1]) per effective voxel: 16 bytes, the
    /// paper's (x, y, z, value) texel. Grouped by brick, by value inside a brick.
    pub voxels: Vec<[f32; 4]>,
    pub bricks: Vec<Brick>,
    tree: Node,
    pub dims: [usize; 3],
    pub origin: [f64; 3],
    pub spacing: [f64; 3],
    /// World length of one kernel unit (the largest grid spacing).
    pub kernel_unit: f64,
    /// Cell volume / kernel_unit³: scales the footprints so kernels on the lattice sum to 1.
    pub density_scale: f64,
    /// The mesh was resampled (it carried no grid).
    pub resampled: bool,
    /// Grid points considered (inside the data).
    pub grid_points: u64,
    /// Voxels whose kernel reaches past their brick into another (drawn out of order, §4).
    pub border_voxels: u64,
    /// Bounding box (world) of the effective voxels.
    pub min: [f64; 3],
    pub max: [f64; 3],
}

/// Grid dimensions for resampling a mesh: `n` points along its longest side, the others in
/// proportion, so that the spacing is (nearly) the same on every axis.
pub fn resample_dims(mesh: &TetMesh, n: usize) -> [usize; 3] {
    let e = mesh.bounds().extent();
    let emax = e.iter().copied().fold(0.0, f64::max).max(1e-30);
    e.map(|x| ((n as f64 - 1.0) * x / emax).round() as usize + 1)
        .map(|d| d.max(2))
}

impl VoxelSet {
    /// The voxels of `mesh`: its source grid (only the grid points its tets use) or, without
    /// one, the mesh resampled with `grid` points along its longest side (only points inside
    /// it). A voxel is effective when κ of its normalised value is > 0. Bricks hold at most
    /// `brick_cap` voxels.
    pub fn new(mesh: &TetMesh, optics: &Optics, grid: usize, brick_cap: usize) -> VoxelSet {
        let owned;
        let (g, inside, resampled);
        match &mesh.source_grid {
            Some(source) => {
                let mut used = vec![false; mesh.num_points()];
                for t in &mesh.tets {
                    for &v in t {
                        used[v as usize] = true;
                    }
                }
                inside = used;
                resampled = false;
                g = &**source;
            }
            None => {
                let (gr, ins) = VoxelGrid::resample_with_inside(mesh, resample_dims(mesh, grid));
                owned = gr;
                inside = ins;
                resampled = true;
                g = &owned;
            }
        };
        let grid_points = inside.iter().filter(|&&b| b).count() as u64;
        VoxelSet::select(g, |i| inside[i], grid_points, resampled, optics, brick_cap)
    }

    /// The voxels of a voxel data set: the grid points its tets would use
    /// ([`VoxelVolume::point_is_used`]), without splitting it; the same set as
    /// [`VoxelSet::new`] with the volume's split mesh.
    pub fn from_volume(volume: &VoxelVolume, optics: &Optics, brick_cap: usize) -> VoxelSet {
        let grid_points = volume.footprint().used_points as u64;
        VoxelSet::select(
            volume.grid(),
            |i| volume.point_is_used(i),
            grid_points,
            false,
            optics,
            brick_cap,
        )
    }

    /// The effective voxels of `g` among the points `inside` accepts (`grid_points` of them).
    fn select(
        g: &VoxelGrid,
        inside: impl Fn(usize) -> bool + Sync,
        grid_points: u64,
        resampled: bool,
        optics: &Optics,
        brick_cap: usize,
    ) -> VoxelSet {
        let tf = &optics.tf;
        // The normalised value of a grid value, if its κ is > 0.
        let classify = |v: f32| {
            let s = optics.normalise(v as f64);
            (tf.kappa_at(s) > 0.0).then_some(s as f32)
        };
        // A grid of 16-bit levels has at most 2^16 values: each is classified once, not once
        // per point (StagBeetle: 342 M points).
        let per_level: Option<(&[u16], Vec<Option<f32>>)> = match &g.values {
            GridValues::Levels { levels, step } => Some((
                levels,
                (0..=u16::MAX).map(|l| classify(l as f32 * step)).collect(),
            )),
            GridValues::F32(_) => None,
        };
        // κ first: on a large volume most points are empty, and `inside` may cost more.
        let mut chosen: Vec<(f32, u32)> = (0..g.num_voxels())
            .into_par_iter()
            .filter_map(|i| {
                let s = match &per_level {
                    Some((levels, table)) => table[levels[i] as usize],
                    None => classify(g.values.get(i)),
                }?;
                inside(i).then_some((s, i as u32))
            })
            .collect();
        // The paper's list of relevant voxels sorted by value (ties by grid index).
        chosen.par_sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let kernel_unit = g.spacing.iter().copied().fold(0.0, f64::max).max(1e-30);
        let density_scale = g.spacing.iter().product::<f64>() / kernel_unit.powi(3);

        let dims = g.dims;
        let cap = brick_cap.max(1);
        let mut bricks = vec![];
        let mut ordered: Vec<(f32, u32)> = Vec::with_capacity(chosen.len());
        let tree = build(&chosen, [0; 3], dims, cap, dims, &mut bricks, &mut ordered);
        drop(chosen);
        let voxels: Vec<[f32; 4]> = ordered
            .par_iter()
            .map(|&(s, i)| {
                let i = i as usize;
                let p = g.point(
                    i % dims[0],
                    (i / dims[0]) % dims[1],
                    i / (dims[0] * dims[1]),
                );
                [p[0] as f32, p[1] as f32, p[2] as f32, s]
            })
            .collect();
        let mut min = [f64::INFINITY; 3];
        let mut max = [f64::NEG_INFINITY; 3];
        for v in &voxels {
            for a in 0..3 {
                min[a] = min[a].min(v[a] as f64);
                max[a] = max[a].max(v[a] as f64);
            }
        }
        VoxelSet {
            voxels,
            bricks,
            tree,
            dims,
            origin: g.origin,
            spacing: g.spacing,
            kernel_unit,
            density_scale,
            resampled,
            grid_points,
            border_voxels: 0,
            min,
            max,
        }
    }

    /// A perturbation for the positive control of the bricks' image claim: every other brick
    /// (the second, the fourth, …) drawn `voxels` grid spacings off along x; its bounds grow
    /// with it. Nothing moves with one brick or `voxels` = 0.
    pub fn misalign(&mut self, voxels: u32) {
        if voxels == 0 {
            return;
        }
        let dx = (f64::from(voxels) * self.spacing[0]) as f32;
        for b in self.bricks.iter().skip(1).step_by(2) {
            for v in &mut self.voxels[b.range.clone()] {
                v[0] += dx;
            }
        }
        for v in &self.voxels {
            self.min[0] = self.min[0].min(v[0] as f64);
            self.max[0] = self.max[0].max(v[0] as f64);
        }
    }

    /// Voxels within `radius` kernel units of an inner brick face.
    pub fn count_border_voxels(&self, radius: f64) -> u64 {
        if self.bricks.len() <= 1 {
            return 0;
        }
        let r = radius * self.kernel_unit;
        self.bricks
            .par_iter()
            .map(|b| {
                self.voxels[b.range.clone()]
                    .iter()
                    .filter(|v| {
                        (0..3).any(|a| {
                            let x = v[a] as f64;
                            let face =
                                |i: usize| self.origin[a] + (i as f64 - 0.5) * self.spacing[a];
                            (b.lo[a] > 0 && x - face(b.lo[a]) < r)
                                || (b.hi[a] < self.dims[a] && face(b.hi[a]) - x < r)
                        })
                    })
                    .count() as u64
            })
            .sum()
    }

    /// Brick indices front to back for a camera at `eye` (perspective) or looking along
    /// `forward` (orthographic): in each octree node the children in the order i XOR near,
    /// which never draws a box before one that can occlude it.
    pub fn brick_order(&self, eye: [f64; 3], forward: [f64; 3], perspective: bool) -> Vec<usize> {
        let mut out = vec![];
        self.visit(&self.tree, eye, forward, perspective, &mut out);
        out
    }

    fn visit(&self, n: &Node, eye: [f64; 3], fwd: [f64; 3], persp: bool, out: &mut Vec<usize>) {
        match n {
            Node::Leaf(b) => out.push(*b),
            Node::Split { mid, children } => {
                let mut near = 0;
                for a in 0..3 {
                    let plane = self.origin[a] + (mid[a] as f64 - 0.5) * self.spacing[a];
                    let high_is_near = if persp { eye[a] >= plane } else { fwd[a] < 0.0 };
                    if high_is_near {
                        near |= 1 << a;
                    }
                }
                for i in 0..8 {
                    if let Some(c) = &children[i ^ near] {
                        self.visit(c, eye, fwd, persp, out);
                    }
                }
            }
        }
    }

    pub fn largest_brick(&self) -> usize {
        self.bricks.iter().map(|b| b.range.len()).max().unwrap_or(0)
    }
}

/// Splits the box [lo, hi) into octants until each holds at most `cap` voxels.
fn build(
    list: &[(f32, u32)],
    lo: [usize; 3],
    hi: [usize; 3],
    cap: usize,
    dims: [usize; 3],
    bricks: &mut Vec<Brick>,
    ordered: &mut Vec<(f32, u32)>,
) -> Node {
    let single = (0..3).all(|a| hi[a] - lo[a] <= 1);
    if list.len() <= cap || single {
        let start = ordered.len();
        ordered.extend_from_slice(list);
        bricks.push(Brick {
            lo,
            hi,
            range: start..ordered.len(),
        });
        return Node::Leaf(bricks.len() - 1);
    }
    let mid = [0, 1, 2].map(|a| (lo[a] + hi[a]).div_ceil(2));
    let mut parts: Vec<Vec<(f32, u32)>> = vec![vec![]; 8];
    for &(s, i) in list {
        let i_us = i as usize;
        let c = [
            i_us % dims[0],
            (i_us / dims[0]) % dims[1],
            i_us / (dims[0] * dims[1]),
        ];
        let o = (0..3)
            .map(|a| ((c[a] >= mid[a]) as usize) << a)
            .sum::<usize>();
        parts[o].push((s, i));
    }
    let children = parts
        .iter()
        .enumerate()
        .map(|(o, p)| {
            if p.is_empty() {
                return None;
            }
            let clo = [0, 1, 2].map(|a| if o >> a & 1 == 1 { mid[a] } else { lo[a] });
            let chi = [0, 1, 2].map(|a| if o >> a & 1 == 1 { hi[a] } else { mid[a] });
            Some(build(p, clo, chi, cap, dims, bricks, ordered))
        })
        .collect();
    Node::Split { mid, children }
}

#[cfg(test)]
mod tests {
    use super::*;
    use render_core::TransferFunction;

    /// The per-level classification of a 16-bit grid selects what classifying each point's
    /// value selects (the same grid held as f32).
    #[test]
    fn a_levels_grid_selects_the_voxels_of_its_f32_values() {
        let levels = datasets::standins::splat_volume([21, 17, 13], 700, 9);
        let values: Vec<f32> = levels.values.iter().collect();
        let f32_grid = VoxelGrid {
            values: values.clone().into(),
            ..levels.clone()
        };
        let bounds = datasets::Aabb {
            min: levels.point(0, 0, 0),
            max: levels.point(20, 16, 12),
        };
        let range = values
            .iter()
            .fold((f32::MAX, f32::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        for tf in ["zero-floor", "low-opacity"] {
            let tf = TransferFunction::preset(tf).unwrap();
            let optics = Optics::for_extent(tf, &bounds, range);
            let select = |g: &VoxelGrid| VoxelSet::select(g, |_| true, 0, false, &optics, 256);
            let (a, b) = (select(&levels), select(&f32_grid));
            assert!(!a.voxels.is_empty());
            assert_eq!(a.voxels, b.voxels);
            assert_eq!(a.bricks, b.bricks);
        }
    }

    /// The positive control's perturbation moves exactly every other brick, by one grid
    /// spacing along x, and nothing else; with one brick or 0 it moves nothing.
    #[test]
    fn misalign_moves_every_other_brick_by_whole_voxels() {
        let grid = datasets::standins::splat_volume([21, 17, 13], 700, 9);
        let bounds = datasets::Aabb {
            min: grid.point(0, 0, 0),
            max: grid.point(20, 16, 12),
        };
        let optics = Optics::for_extent(
            TransferFunction::preset("zero-floor").unwrap(),
            &bounds,
            (0.0, 700.0),
        );
        let set = VoxelSet::select(&grid, |_| true, 0, false, &optics, 256);
        assert!(set.bricks.len() >= 4, "{} bricks", set.bricks.len());
        let mut moved = set.clone();
        moved.misalign(1);
        let dx = grid.spacing[0] as f32;
        for (i, b) in set.bricks.iter().enumerate() {
            for j in b.range.clone() {
                let (was, now) = (set.voxels[j], moved.voxels[j]);
                let shift = if i % 2 == 1 { dx } else { 0.0 };
                assert_eq!(now[0], was[0] + shift, "brick {i}");
                assert_eq!(&now[1..], &was[1..]);
            }
        }
        assert!(moved.max[0] >= set.max[0] && moved.min[0] <= set.min[0]);
        let mut same = set.clone();
        same.misalign(0);
        assert_eq!(same.voxels, set.voxels);
        let mut one = VoxelSet::select(&grid, |_| true, 0, false, &optics, usize::MAX);
        let before = one.voxels.clone();
        one.misalign(1);
        assert_eq!(one.bricks.len(), 1);
        assert_eq!(one.voxels, before);
    }
}
