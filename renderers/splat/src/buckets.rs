//! Slabs and buckets (Grau & Tost §3.1, §3.5): slabs are parallel to the image plane, `Δ`
//! deep in view depth; a bucket is the run of depth-sorted voxels whose *centre* lies in one
//! slab, so every voxel is in exactly one bucket. The bucket table holds, per slab, the end
//! (one past the last voxel) of its bucket in the sorted list.
//!
//! This module is the CPU side: the slab geometry of a frame, the CPU twin of the GPU
//! boundary pass (`compute.wgsl`, `boundaries`), and the CPU-bucket pipeline of the paper's
//! "CPU FPS" column (view transform, sort and bucket table on the host, uploaded each frame).

use render_core::sort::{radix_sort_indices, RadixScratch};

/// Where the slabs of one frame lie: slab `i` covers view depths [d0 + iΔ, d0 + (i+1)Δ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlabGeometry {
    pub d0: f32,
    pub inv_delta: f32,
    pub num_slabs: u32,
    /// Kernel radius in slabs: slab i splats the buckets i − r … i + r.
    pub radius_slabs: u32,
}

/// View depth of a point, in f32 exactly as the shaders compute it: −(row 2 of the view
/// matrix · (p, 1)).
pub fn depth(row: [f32; 4], p: [f32; 4]) -> f32 {
    -(row[0] * p[0] + row[1] * p[1] + row[2] * p[2] + row[3])
}

impl SlabGeometry {
    /// Slabs covering depths [dmin − margin, dmax + margin], `delta` deep.
    pub fn new(dmin: f64, dmax: f64, margin: f64, delta: f64, radius_slabs: u32) -> SlabGeometry {
        let d0 = dmin - margin - 0.5 * delta;
        let num = ((dmax + margin - d0) / delta).floor() as u32 + 2;
        SlabGeometry {
            d0: d0 as f32,
            inv_delta: (1.0 / delta) as f32,
            num_slabs: num,
            radius_slabs,
        }
    }

    /// Slab of a depth (the twin of `slab_of` in `compute.wgsl`).
    pub fn slab_of(&self, d: f32) -> u32 {
        let s = ((d - self.d0) * self.inv_delta).floor();
        (s.max(0.0) as u32).min(self.num_slabs - 1)
    }

    /// The voxel range of bucket `b` alone: the voxels whose slab is `b`.
    pub fn bucket_range(&self, ends: &[u32], b: u32) -> std::ops::Range<u32> {
        let start = if b > 0 { ends[b as usize - 1] } else { 0 };
        start..ends[b as usize].max(start)
    }

    /// Sheets a pass holds at once: slab i splats buckets i − r … i + r, so a bucket's voxels
    /// belong to 2r + 1 consecutive sheets (a ring, `splat.wgsl`).
    pub fn ring(&self) -> u32 {
        2 * self.radius_slabs + 1
    }

    /// The voxel range slab `i` splats: from the start of bucket i − r to the end of i + r.
    pub fn splat_range(&self, ends: &[u32], i: u32) -> std::ops::Range<u32> {
        let r = self.radius_slabs;
        let start = if i > r { ends[(i - r - 1) as usize] } else { 0 };
        let end = ends[((i + r).min(self.num_slabs - 1)) as usize];
        start..end.max(start)
    }
}

/// The bucket table of depth-sorted voxels: `ends[s]` = number of voxels whose slab is ≤ s.
/// Written as the GPU pass does it, from the boundaries: voxel i is a boundary when voxel
/// i + 1 lies in a later slab, and then ends the buckets slab(i) … slab(i+1) − 1.
pub fn bucket_ends(sorted_depths: &[f32], g: &SlabGeometry) -> Vec<u32> {
    let n = sorted_depths.len();
    let mut ends = vec![0u32; g.num_slabs as usize];
    if n == 0 {
        return ends;
    }
    for i in 0..n {
        let s = g.slab_of(sorted_depths[i]);
        let next = if i + 1 < n {
            g.slab_of(sorted_depths[i + 1])
        } else {
            g.num_slabs
        };
        for e in &mut ends[s as usize..next as usize] {
            *e = i as u32 + 1;
        }
    }
    // Slabs before the first voxel's end at 0 (already).
    ends
}

/// The CPU-bucket pipeline of one brick: depths, stable radix sort (render-core's, the
/// paper's CPU baseline sorts on the host), bucket table, gather.
#[derive(Default)]
pub struct CpuBuckets {
    keys: Vec<f32>,
    order: Vec<u32>,
    scratch: RadixScratch,
    pub sorted_keys: Vec<f32>,
    piece: Vec<[f32; 4]>,
}

impl CpuBuckets {
    /// Sorts `voxels` by depth and returns the bucket table; [`Self::gather`] then writes
    /// them in that order.
    pub fn run(&mut self, voxels: &[[f32; 4]], depth_row: [f32; 4], g: &SlabGeometry) -> Vec<u32> {
        use rayon::prelude::*;
        self.keys.clear();
        self.keys
            .par_extend(voxels.par_iter().map(|&v| depth(depth_row, v)));
        radix_sort_indices(&self.keys, &mut self.order, &mut self.scratch);
        self.sorted_keys.clear();
        self.sorted_keys
            .par_extend(self.order.par_iter().map(|&i| self.keys[i as usize]));
        bucket_ends(&self.sorted_keys, g)
    }

    /// The voxels of the last [`Self::run`] in depth order, `PIECE` at a time: `write(first,
    /// piece)` uploads each, so the host holds one piece of the sorted set, not all of it.
    pub fn gather(&mut self, voxels: &[[f32; 4]], mut write: impl FnMut(usize, &[[f32; 4]])) {
        use rayon::prelude::*;
        // 16 MB: large enough that each upload streams, small beside the voxels themselves.
        const PIECE: usize = 1 << 20;
        for (p, order) in self.order.chunks(PIECE).enumerate() {
            self.piece.clear();
            self.piece
                .par_extend(order.par_iter().map(|&i| voxels[i as usize]));
            write(p * PIECE, &self.piece);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_partition_the_sorted_voxels() {
        let g = SlabGeometry::new(1.0, 5.0, 0.5, 1.0, 2);
        let depths = [1.0f32, 1.2, 1.9, 3.5, 3.6, 5.0];
        let ends = bucket_ends(&depths, &g);
        assert_eq!(ends.len(), g.num_slabs as usize);
        for (i, d) in depths.iter().enumerate() {
            let s = g.slab_of(*d) as usize;
            let start = if s == 0 { 0 } else { ends[s - 1] };
            assert!((start..ends[s]).contains(&(i as u32)), "voxel {i}");
        }
        assert_eq!(*ends.last().unwrap(), depths.len() as u32);
        // Slab i splats every voxel whose centre is within r slabs.
        let i = g.slab_of(3.5);
        let r = g.splat_range(&ends, i);
        let want: Vec<u32> = (0..6u32)
            .filter(|&v| g.slab_of(depths[v as usize]).abs_diff(i) <= 2)
            .collect();
        assert_eq!(r.collect::<Vec<_>>(), want);
    }
}
