//! CPU sorts of float keys. The LSD radix sort is the one HAVS §5.1 uses: each f32 key is
//! mapped to a u32 whose unsigned order is the float order, then four 8-bit counting passes.
//!
//! `radix.rs` the radix sorts (serial as the paper ran it, and split over rayon's threads),
//! `comparison.rs` the textbook comparison sorts of HAVS Table 1 and the merge sort,
//! `bucket.rs` fragment PT's bucket sort into depth slabs.

mod bucket;
mod comparison;
mod radix;

pub use bucket::{bucket_sort_indices, slab_of, DEFAULT_SLABS};
pub use comparison::{
    heapsort, heapsort_indices, merge_sort, merge_sort_indices, quicksort, quicksort_indices,
    shellsort, shellsort_indices, std_sort_indices,
};
pub use radix::{
    radix_sort_indices, radix_sort_indices_descending, radix_sort_indices_parallel,
    radix_sort_indices_serial, radix_sort_packed, RadixScratch, PARALLEL_RADIX_MIN_KEYS,
};

/// Maps an f32 to a u32 with the same ordering (HAVS §5.1): flip the sign bit of positives,
/// all bits of negatives.
#[inline]
pub fn float_to_ordered_u32(f: f32) -> u32 {
    let b = f.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// The CPU sorts compared in HAVS Table 1 (and the bucket/merge sorts of fragment PT), by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CpuSort {
    Shell,
    Heap,
    Quick,
    Radix,
    Std,
    Merge,
}

impl CpuSort {
    /// The algorithms of HAVS Table 1, in the paper's row order, then the standard library's.
    pub const TABLE1: [CpuSort; 5] = [
        CpuSort::Shell,
        CpuSort::Heap,
        CpuSort::Quick,
        CpuSort::Radix,
        CpuSort::Std,
    ];

    pub fn name(self) -> &'static str {
        match self {
            CpuSort::Shell => "shellsort",
            CpuSort::Heap => "heapsort",
            CpuSort::Quick => "quicksort",
            CpuSort::Radix => "radix sort",
            CpuSort::Std => "std sort_unstable_by",
            CpuSort::Merge => "merge sort",
        }
    }

    /// Sorts indices by ascending key. `Std` is unstable on equal keys; all others give the
    /// stable order.
    pub fn sort_indices(self, keys: &[f32], indices: &mut Vec<u32>) {
        match self {
            CpuSort::Shell => shellsort_indices(keys, indices),
            CpuSort::Heap => heapsort_indices(keys, indices),
            CpuSort::Quick => quicksort_indices(keys, indices),
            CpuSort::Radix => radix_sort_indices(keys, indices, &mut RadixScratch::default()),
            CpuSort::Std => std_sort_indices(keys, indices),
            CpuSort::Merge => merge_sort_indices(keys, false, indices, &mut Vec::new()),
        }
    }
}

#[cfg(test)]
mod tests;
