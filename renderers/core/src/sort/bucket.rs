//! The bucket sort into depth slabs of Marroquim et al. 2006 §4.

/// The default number of depth slabs of the bucket sort (Marroquim et al. 2006 §4: "about 20").
pub const DEFAULT_SLABS: usize = 20;

/// The slab of each key: `slabs` equal-width depth intervals between the smallest and the largest
/// finite key (non-finite keys go to the nearest end).
pub fn slab_of(key: f32, lo: f32, hi: f32, slabs: usize) -> usize {
    // No range (one key, all equal, or no finite key): everything in slab 0.
    if !matches!(hi.partial_cmp(&lo), Some(std::cmp::Ordering::Greater)) {
        return 0;
    }
    let t = ((key - lo) / (hi - lo) * slabs as f32).floor();
    if t.is_nan() || t < 0.0 {
        0
    } else {
        (t as usize).min(slabs - 1)
    }
}

/// Bucket sort into `slabs` depth slabs (Marroquim et al. 2006 §4, used while the camera moves):
/// slabs ascend (`descending`: descend), and within a slab the input order is left as is. That
/// partial order is the point: O(n) with one counting pass, at the price of ordering errors
/// between nearby cells of one slab. Returns the `(lo, hi)` key range the slabs cover.
pub fn bucket_sort_indices(
    keys: &[f32],
    slabs: usize,
    descending: bool,
    indices: &mut Vec<u32>,
) -> (f32, f32) {
    let slabs = slabs.max(1);
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for &k in keys {
        if k.is_finite() {
            lo = lo.min(k);
            hi = hi.max(k);
        }
    }
    let mut count = vec![0u32; slabs + 1];
    let slab = |k: f32| {
        let s = slab_of(k, lo, hi, slabs);
        if descending {
            slabs - 1 - s
        } else {
            s
        }
    };
    for &k in keys {
        count[slab(k) + 1] += 1;
    }
    for s in 0..slabs {
        count[s + 1] += count[s];
    }
    indices.clear();
    indices.resize(keys.len(), 0);
    for (i, &k) in keys.iter().enumerate() {
        let s = slab(k);
        indices[count[s] as usize] = i as u32;
        count[s] += 1;
    }
    (lo, hi)
}
