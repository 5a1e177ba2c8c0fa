// ---------------------------------------------------------------------------------------------
// The classic comparison sorts of HAVS Table 1 (Callahan et al. 2005 §5.1 compare shellsort,
// heapsort, quicksort and radix sort on 1 M floats), plus the sorts of Marroquim et al. 2006 §4
// (bucket sort while the camera moves, merge sort for still frames).
//
// They are written by hand on purpose: the point of Table 1 is to compare the textbook
// algorithms themselves, which no crate exposes as such (std and rayon hide theirs behind one
// `sort`). Each `*_sort_indices` wrapper sorts the same items: a key/index pair packed into a
// u64, `(float_to_ordered_u32(key) << 32) | index`. Integer comparison of the packed pair is the
// float order of the keys (HAVS §5.1's mapping), with ties broken by index, so every sort here
// yields exactly the stable order of the radix sort, and the pair stays in one cache line slot.
// ---------------------------------------------------------------------------------------------

use super::float_to_ordered_u32;

/// Packs keys and their indices as `ordered(key) << 32 | index` (ascending key order).
fn packed_pairs(keys: &[f32], descending: bool) -> Vec<u64> {
    let flip = if descending { u32::MAX } else { 0 };
    keys.iter()
        .enumerate()
        .map(|(i, &k)| (((float_to_ordered_u32(k) ^ flip) as u64) << 32) | i as u64)
        .collect()
}

fn unpack_indices(pairs: &[u64], indices: &mut Vec<u32>) {
    indices.clear();
    indices.extend(pairs.iter().map(|&p| p as u32));
}

/// Shellsort with Tokuda's gap sequence (h_k = ⌈(9^k − 4^k) / (5·4^(k−1))⌉: 1, 4, 9, 20, 46,
/// 103, …), one of the best known empirically (Tokuda 1992; Ciura 2001's is similar but only
/// tabulated up to 1750).
pub fn shellsort<T: Copy>(v: &mut [T], less: impl Fn(&T, &T) -> bool) {
    let n = v.len();
    let mut gaps = Vec::new();
    let mut k = 1u32;
    loop {
        let num = 9f64.powi(k as i32) - 4f64.powi(k as i32);
        let h = (num / (5.0 * 4f64.powi(k as i32 - 1))).ceil() as usize;
        if h >= n.max(2) {
            break;
        }
        gaps.push(h);
        k += 1;
    }
    for &gap in gaps.iter().rev() {
        for i in gap..n {
            let x = v[i];
            let mut j = i;
            while j >= gap && less(&x, &v[j - gap]) {
                v[j] = v[j - gap];
                j -= gap;
            }
            v[j] = x;
        }
    }
}

/// Heapsort (Williams 1964, Floyd's bottom-up heap construction): a max-heap, then repeated
/// extraction of the maximum to the end.
pub fn heapsort<T: Copy>(v: &mut [T], less: impl Fn(&T, &T) -> bool) {
    let n = v.len();
    // Moves v[root] down within v[..end] until the heap property holds.
    let sift_down = |v: &mut [T], mut root: usize, end: usize| {
        let x = v[root];
        loop {
            let mut child = 2 * root + 1;
            if child >= end {
                break;
            }
            if child + 1 < end && less(&v[child], &v[child + 1]) {
                child += 1;
            }
            if !less(&x, &v[child]) {
                break;
            }
            v[root] = v[child];
            root = child;
        }
        v[root] = x;
    };
    for root in (0..n / 2).rev() {
        sift_down(v, root, n);
    }
    for end in (1..n).rev() {
        v.swap(0, end);
        sift_down(v, 0, end);
    }
}

/// Ranges this short are finished by insertion sort (quicksort's classic cut-off; Sedgewick).
const QUICKSORT_CUTOFF: usize = 16;

fn insertion_sort<T: Copy>(v: &mut [T], less: &impl Fn(&T, &T) -> bool) {
    for i in 1..v.len() {
        let x = v[i];
        let mut j = i;
        while j > 0 && less(&x, &v[j - 1]) {
            v[j] = v[j - 1];
            j -= 1;
        }
        v[j] = x;
    }
}

/// Quicksort (Hoare 1962) with median-of-three pivots and insertion sort for short ranges; it
/// recurses into the smaller part and loops on the larger, so the stack stays O(log n).
pub fn quicksort<T: Copy>(v: &mut [T], less: impl Fn(&T, &T) -> bool) {
    quicksort_rec(v, &less);
}

fn quicksort_rec<T: Copy>(mut v: &mut [T], less: &impl Fn(&T, &T) -> bool) {
    while v.len() > QUICKSORT_CUTOFF {
        let n = v.len();
        let mid = n / 2;
        // Median of three, left in v[mid]; v[0] ≤ v[mid] ≤ v[n−1] serve as sentinels.
        if less(&v[mid], &v[0]) {
            v.swap(mid, 0);
        }
        if less(&v[n - 1], &v[0]) {
            v.swap(n - 1, 0);
        }
        if less(&v[n - 1], &v[mid]) {
            v.swap(n - 1, mid);
        }
        let pivot = v[mid];
        // Hoare partition.
        let (mut i, mut j) = (0usize, n - 1);
        loop {
            while less(&v[i], &pivot) {
                i += 1;
            }
            while less(&pivot, &v[j]) {
                j -= 1;
            }
            if i >= j {
                break;
            }
            v.swap(i, j);
            i += 1;
            j -= 1;
        }
        // v[..=j] ≤ pivot ≤ v[j+1..]
        let (left, right) = v.split_at_mut(j + 1);
        if left.len() < right.len() {
            quicksort_rec(left, less);
            v = right;
        } else {
            quicksort_rec(right, less);
            v = left;
        }
    }
    insertion_sort(v, less);
}

/// Stable bottom-up merge sort (von Neumann), ping-ponging between `v` and `scratch`. Runs of
/// `QUICKSORT_CUTOFF` are first sorted by insertion sort.
pub fn merge_sort<T: Copy>(v: &mut [T], scratch: &mut Vec<T>, less: impl Fn(&T, &T) -> bool) {
    let n = v.len();
    if n <= 1 {
        return;
    }
    for run in v.chunks_mut(QUICKSORT_CUTOFF) {
        insertion_sort(run, &less);
    }
    scratch.clear();
    scratch.extend_from_slice(v);
    let mut width = QUICKSORT_CUTOFF;
    // `in_v`: the current runs are in `v` (else in `scratch`).
    let mut in_v = true;
    while width < n {
        let (src, dst): (&[T], &mut [T]) = if in_v {
            (&*v, &mut scratch[..])
        } else {
            (&scratch[..], &mut *v)
        };
        let mut lo = 0;
        while lo < n {
            let mid = (lo + width).min(n);
            let hi = (lo + 2 * width).min(n);
            let (mut a, mut b, mut o) = (lo, mid, lo);
            while a < mid && b < hi {
                // `<=` on the left run keeps equal items in input order (stability).
                if less(&src[b], &src[a]) {
                    dst[o] = src[b];
                    b += 1;
                } else {
                    dst[o] = src[a];
                    a += 1;
                }
                o += 1;
            }
            dst[o..o + (mid - a)].copy_from_slice(&src[a..mid]);
            o += mid - a;
            dst[o..o + (hi - b)].copy_from_slice(&src[b..hi]);
            lo = hi;
        }
        in_v = !in_v;
        width *= 2;
    }
    if !in_v {
        v.copy_from_slice(scratch);
    }
}

/// Indices sorted by ascending key with [`shellsort`].
pub fn shellsort_indices(keys: &[f32], indices: &mut Vec<u32>) {
    let mut p = packed_pairs(keys, false);
    shellsort(&mut p, |a, b| a < b);
    unpack_indices(&p, indices);
}

/// Indices sorted by ascending key with [`heapsort`].
pub fn heapsort_indices(keys: &[f32], indices: &mut Vec<u32>) {
    let mut p = packed_pairs(keys, false);
    heapsort(&mut p, |a, b| a < b);
    unpack_indices(&p, indices);
}

/// Indices sorted by ascending key with [`quicksort`].
pub fn quicksort_indices(keys: &[f32], indices: &mut Vec<u32>) {
    let mut p = packed_pairs(keys, false);
    quicksort(&mut p, |a, b| a < b);
    unpack_indices(&p, indices);
}

/// Indices sorted by ascending key (`descending`: by descending key) with [`merge_sort`]; ties
/// keep ascending index order either way.
pub fn merge_sort_indices(
    keys: &[f32],
    descending: bool,
    indices: &mut Vec<u32>,
    scratch: &mut Vec<u64>,
) {
    let mut p = packed_pairs(keys, descending);
    merge_sort(&mut p, scratch, |a, b| a < b);
    unpack_indices(&p, indices);
}

/// The baseline every user would write: the standard library's pattern-defeating quicksort,
/// `sort_unstable_by` on (key, index) pairs with `f32::total_cmp`.
pub fn std_sort_indices(keys: &[f32], indices: &mut Vec<u32>) {
    let mut p: Vec<(f32, u32)> = keys
        .iter()
        .enumerate()
        .map(|(i, &k)| (k, i as u32))
        .collect();
    p.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    indices.clear();
    indices.extend(p.iter().map(|x| x.1));
}
