//! CPU sorts of float keys. The LSD radix sort is the one HAVS §5.1 uses: each f32 key is
//! mapped to a u32 whose unsigned order is the float order, then four 8-bit counting passes.

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

/// Sorts `indices` so that `keys[indices[i]]` ascends, with an LSD radix sort over the ordered
/// u32 images of the keys (HAVS §5.1): stable, one read of the keys builds every digit histogram,
/// passes whose digit is the same for all keys are skipped. `scratch` is reused between frames.
///
/// From [`PARALLEL_RADIX_MIN_KEYS`] keys on, and when rayon has more than one thread, each pass
/// is split over the threads ([`radix_sort_indices_parallel`]); the result is the same
/// permutation (the sort is stable either way).
pub fn radix_sort_indices(keys: &[f32], indices: &mut Vec<u32>, scratch: &mut RadixScratch) {
    radix_sort_dispatch(keys, 0, indices, scratch);
}

/// The single-threaded sort exactly as HAVS §5.1 ran it (four 8-bit passes on one core); the
/// sort bench reports it beside the parallel one.
pub fn radix_sort_indices_serial(keys: &[f32], indices: &mut Vec<u32>, scratch: &mut RadixScratch) {
    radix_sort_8bit(keys, 0, indices, scratch);
}

/// Below this many keys one thread is faster than splitting (the per-part histograms and
/// the rayon hand-off cost more than they save).
pub const PARALLEL_RADIX_MIN_KEYS: usize = 1 << 16;

fn radix_sort_dispatch(
    keys: &[f32],
    flip: u32,
    indices: &mut Vec<u32>,
    scratch: &mut RadixScratch,
) {
    if keys.len() >= PARALLEL_RADIX_MIN_KEYS && rayon::current_num_threads() > 1 {
        radix_sort_parallel_8bit(keys, flip, indices, scratch);
    } else {
        radix_sort_8bit(keys, flip, indices, scratch);
    }
}

/// [`radix_sort_indices`] split over rayon's threads whatever the input size (ascending).
pub fn radix_sort_indices_parallel(
    keys: &[f32],
    indices: &mut Vec<u32>,
    scratch: &mut RadixScratch,
) {
    radix_sort_parallel_8bit(keys, 0, indices, scratch);
}

/// The four 8-bit LSD passes with each pass split over T contiguous parts of its input (T =
/// rayon's threads). Every part counts its own digits; the destination is then cut into
/// (digit, part) runs in digit-major order, so part q's items with digit d land after those of
/// parts < q — exactly where the serial scatter puts them, which keeps the sort stable. The
/// runs are disjoint `&mut` slices (`split_at_mut`), so the threads share nothing and no
/// `unsafe` is needed. Measured on the 2-core bench machine: 1.7–1.8× the serial sort on 1 M
/// keys (benches/sort.rs).
fn radix_sort_parallel_8bit(
    keys: &[f32],
    flip: u32,
    indices: &mut Vec<u32>,
    scratch: &mut RadixScratch,
) {
    use rayon::prelude::*;
    let n = keys.len();
    debug_assert!(n <= u32::MAX as usize);
    let part = n.div_ceil(rayon::current_num_threads()).max(1 << 12);
    // One read of the keys: per part, all four digit histograms.
    let part_hists: Vec<[[u32; 256]; 4]> = keys
        .par_chunks(part)
        .map(|c| {
            let mut h = [[0u32; 256]; 4];
            for &k in c {
                let u = float_to_ordered_u32(k) ^ flip;
                for (p, hp) in h.iter_mut().enumerate() {
                    hp[(u >> (8 * p)) as u8 as usize] += 1;
                }
            }
            h
        })
        .collect();
    let live: Vec<usize> = (0..4)
        .filter(|&p| {
            !(0..256).any(|d| part_hists.iter().map(|h| h[p][d] as usize).sum::<usize>() == n)
        })
        .collect();
    if live.is_empty() {
        indices.clear();
        indices.extend(0..n as u32);
        return;
    }
    // Every element is overwritten: `resize` only fills growth (no 4 MB memset per frame).
    scratch.a.resize(n, 0);
    scratch.b.resize(n, 0);
    indices.resize(n, 0);
    let (mut a, mut b) = (&mut scratch.a, &mut scratch.b);
    for (li, &p) in live.iter().enumerate() {
        let (first, last) = (li == 0, li + 1 == live.len());
        let key_shift = 8 * p as u32;
        let shift = 32 + key_shift;
        let counts: Vec<[u32; 256]> = if first {
            part_hists.iter().map(|h| h[p]).collect()
        } else {
            a.par_chunks(part)
                .map(|c| {
                    let mut h = [0u32; 256];
                    for &x in c {
                        h[(x >> shift) as u8 as usize] += 1;
                    }
                    h
                })
                .collect()
        };
        let digit = |u: u32| (u >> key_shift) as u8 as usize;
        match (first, last) {
            (true, true) => {
                let runs = split_into_runs(&mut indices[..], &counts);
                keys.par_chunks(part)
                    .zip(runs)
                    .enumerate()
                    .for_each(|(q, (c, mut runs))| {
                        let mut at = [0usize; 256];
                        for (i, &k) in c.iter().enumerate() {
                            let d = digit(float_to_ordered_u32(k) ^ flip);
                            runs[d][at[d]] = (q * part + i) as u32;
                            at[d] += 1;
                        }
                    });
            }
            (true, false) => {
                let runs = split_into_runs(&mut b[..], &counts);
                keys.par_chunks(part)
                    .zip(runs)
                    .enumerate()
                    .for_each(|(q, (c, mut runs))| {
                        let mut at = [0usize; 256];
                        for (i, &k) in c.iter().enumerate() {
                            let u = float_to_ordered_u32(k) ^ flip;
                            let d = digit(u);
                            runs[d][at[d]] = ((u as u64) << 32) | (q * part + i) as u64;
                            at[d] += 1;
                        }
                    });
                std::mem::swap(&mut a, &mut b);
            }
            (false, true) => {
                let runs = split_into_runs(&mut indices[..], &counts);
                a.par_chunks(part).zip(runs).for_each(|(c, mut runs)| {
                    let mut at = [0usize; 256];
                    for &x in c {
                        let d = (x >> shift) as u8 as usize;
                        runs[d][at[d]] = x as u32;
                        at[d] += 1;
                    }
                });
            }
            (false, false) => {
                let runs = split_into_runs(&mut b[..], &counts);
                a.par_chunks(part).zip(runs).for_each(|(c, mut runs)| {
                    let mut at = [0usize; 256];
                    for &x in c {
                        let d = (x >> shift) as u8 as usize;
                        runs[d][at[d]] = x;
                        at[d] += 1;
                    }
                });
                std::mem::swap(&mut a, &mut b);
            }
        }
    }
}

/// Cuts `dst` into one run per (part, digit), laid out digit-major (all parts' digit-0 runs,
/// then digit 1, …); returns them grouped by part. `counts[q][d]` is part q's digit-d count.
fn split_into_runs<'a, T>(mut dst: &'a mut [T], counts: &[[u32; 256]]) -> Vec<Vec<&'a mut [T]>> {
    let mut runs: Vec<Vec<&mut [T]>> = counts.iter().map(|_| Vec::with_capacity(256)).collect();
    for d in 0..256 {
        for (q, c) in counts.iter().enumerate() {
            let (run, rest) = std::mem::take(&mut dst).split_at_mut(c[d] as usize);
            runs[q].push(run);
            dst = rest;
        }
    }
    debug_assert!(dst.is_empty());
    runs
}

/// Buffers the radix sort reuses from frame to frame.
#[derive(Debug, Default, Clone)]
pub struct RadixScratch {
    a: Vec<u64>,
    b: Vec<u64>,
}

/// Back-to-front order: indices sorted by descending key (stable: equal keys keep ascending
/// index order). The keys' ordered images are complemented, so it costs the same as ascending.
pub fn radix_sort_indices_descending(
    keys: &[f32],
    indices: &mut Vec<u32>,
    scratch: &mut RadixScratch,
) {
    radix_sort_dispatch(keys, u32::MAX, indices, scratch);
}

/// The radix sort behind [`radix_sort_indices`]: HAVS §5.1's four 8-bit passes over
/// `(ordered(key) ^ flip) << 32 | index` pairs packed in a u64 (one 8-byte item per scatter
/// instead of a key and a value in two arrays). The first pass reads the f32 keys directly, the
/// last writes only the indices. Tuned for 1 M keys (benches/sort.rs):
/// - the histograms are built in two interleaved copies: with real depth keys most keys share
///   their top byte, and a single counter incremented key after key is a chain of dependent
///   load-add-stores;
/// - digits are taken as `u8`, so indexing the 256-entry tables needs no bounds check.
fn radix_sort_8bit(keys: &[f32], flip: u32, indices: &mut Vec<u32>, scratch: &mut RadixScratch) {
    let n = keys.len();
    indices.clear();
    debug_assert!(n <= u32::MAX as usize);
    let mut h = [[[0u32; 256]; 4]; 2];
    let mut pairs = keys.chunks_exact(2);
    for c in &mut pairs {
        let (u, v) = (
            float_to_ordered_u32(c[0]) ^ flip,
            float_to_ordered_u32(c[1]) ^ flip,
        );
        for p in 0..4 {
            h[0][p][(u >> (8 * p)) as u8 as usize] += 1;
            h[1][p][(v >> (8 * p)) as u8 as usize] += 1;
        }
    }
    for &k in pairs.remainder() {
        let u = float_to_ordered_u32(k) ^ flip;
        for p in 0..4 {
            h[0][p][(u >> (8 * p)) as u8 as usize] += 1;
        }
    }
    let mut hist = [[0u32; 256]; 4];
    for p in 0..4 {
        for d in 0..256 {
            hist[p][d] = h[0][p][d] + h[1][p][d];
        }
    }
    // A pass where every key has the same digit changes nothing: skip it.
    let live: Vec<usize> = (0..4)
        .filter(|&p| !hist[p].iter().any(|&c| c as usize == n))
        .collect();
    if live.is_empty() {
        indices.extend(0..n as u32);
        return;
    }
    scratch.a.resize(n, 0);
    scratch.b.resize(n, 0);
    let (mut a, mut b) = (&mut scratch.a, &mut scratch.b);
    let mut offset = [0usize; 256];
    for (li, &p) in live.iter().enumerate() {
        let mut sum = 0usize;
        for (o, &c) in offset.iter_mut().zip(&hist[p]) {
            *o = sum;
            sum += c as usize;
        }
        let (first, last) = (li == 0, li + 1 == live.len());
        let key_shift = 8 * p;
        let shift = 32 + key_shift;
        if first && last {
            indices.resize(n, 0);
            for (i, &k) in keys.iter().enumerate() {
                let d = ((float_to_ordered_u32(k) ^ flip) >> key_shift) as u8 as usize;
                indices[offset[d]] = i as u32;
                offset[d] += 1;
            }
        } else if first {
            for (i, &k) in keys.iter().enumerate() {
                let u = float_to_ordered_u32(k) ^ flip;
                let d = (u >> key_shift) as u8 as usize;
                a[offset[d]] = ((u as u64) << 32) | i as u64;
                offset[d] += 1;
            }
        } else if last {
            indices.resize(n, 0);
            for &x in a.iter() {
                let d = (x >> shift) as u8 as usize;
                indices[offset[d]] = x as u32;
                offset[d] += 1;
            }
        } else {
            for &x in a.iter() {
                let d = (x >> shift) as u8 as usize;
                b[offset[d]] = x;
                offset[d] += 1;
            }
            std::mem::swap(&mut a, &mut b);
        }
    }
}

/// LSD radix sort of `(ordered(key) ^ flip) << 32 | index` pairs packed in a u64, so that each
/// scatter moves one 8-byte item instead of a key and a value in two arrays (one cache line
/// stream per digit instead of two). The first pass reads the f32 keys directly and the last
/// writes only the indices.
/// `BITS`-bit digits (e.g. 11: three passes, the alternative the issue suggests; the bench
/// compares it with the 8-bit sort), otherwise as [`radix_sort_indices`].
pub fn radix_sort_packed<const BITS: u32>(
    keys: &[f32],
    flip: u32,
    indices: &mut Vec<u32>,
    scratch: &mut RadixScratch,
) {
    let n = keys.len();
    let passes = 32u32.div_ceil(BITS) as usize;
    let radix = 1usize << BITS;
    let mask = (radix - 1) as u32;
    indices.clear();
    debug_assert!(n <= u32::MAX as usize);
    // One read of the keys builds all histograms.
    let mut hist = vec![0u32; passes * radix];
    for &k in keys {
        let u = float_to_ordered_u32(k) ^ flip;
        for p in 0..passes {
            hist[p * radix + ((u >> (BITS as usize * p)) & mask) as usize] += 1;
        }
    }
    // A pass where every key has the same digit changes nothing: skip it.
    let live: Vec<usize> = (0..passes)
        .filter(|&p| {
            !hist[p * radix..(p + 1) * radix]
                .iter()
                .any(|&c| c as usize == n)
        })
        .collect();
    if live.is_empty() {
        indices.extend(0..n as u32);
        return;
    }
    scratch.a.resize(n, 0);
    scratch.b.resize(n, 0);
    let (mut a, mut b) = (&mut scratch.a, &mut scratch.b);
    let mut offset = vec![0usize; radix];
    for (li, &p) in live.iter().enumerate() {
        let mut sum = 0usize;
        for (o, &h) in offset.iter_mut().zip(&hist[p * radix..(p + 1) * radix]) {
            *o = sum;
            sum += h as usize;
        }
        let first = li == 0;
        let last = li + 1 == live.len();
        let key_shift = BITS as usize * p;
        let shift = 32 + key_shift;
        match (first, last) {
            (true, true) => {
                indices.resize(n, 0);
                for (i, &k) in keys.iter().enumerate() {
                    let d = (((float_to_ordered_u32(k) ^ flip) >> key_shift) & mask) as usize;
                    indices[offset[d]] = i as u32;
                    offset[d] += 1;
                }
            }
            (true, false) => {
                for (i, &k) in keys.iter().enumerate() {
                    let u = float_to_ordered_u32(k) ^ flip;
                    let d = ((u >> key_shift) & mask) as usize;
                    a[offset[d]] = ((u as u64) << 32) | i as u64;
                    offset[d] += 1;
                }
            }
            (false, true) => {
                indices.resize(n, 0);
                for &x in a.iter() {
                    let d = ((x >> shift) as u32 & mask) as usize;
                    indices[offset[d]] = x as u32;
                    offset[d] += 1;
                }
            }
            (false, false) => {
                for &x in a.iter() {
                    let d = ((x >> shift) as u32 & mask) as usize;
                    b[offset[d]] = x;
                    offset[d] += 1;
                }
                std::mem::swap(&mut a, &mut b);
            }
        }
    }
}

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
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn ordered_u32_preserves_order(a in proptest::num::f32::NORMAL | proptest::num::f32::ZERO | proptest::num::f32::SUBNORMAL,
                                        b in proptest::num::f32::NORMAL | proptest::num::f32::ZERO | proptest::num::f32::SUBNORMAL) {
            if a < b { prop_assert!(float_to_ordered_u32(a) < float_to_ordered_u32(b)); }
        }

        #[test]
        fn radix_sort_agrees_with_std(keys in proptest::collection::vec(-1e6f32..1e6, 0..2000)) {
            let mut idx = Vec::new();
            radix_sort_indices(&keys, &mut idx, &mut RadixScratch::default());
            let mut expect: Vec<u32> = (0..keys.len() as u32).collect();
            expect.sort_by(|&i, &j| keys[i as usize].total_cmp(&keys[j as usize]));
            let got: Vec<f32> = idx.iter().map(|&i| keys[i as usize]).collect();
            let want: Vec<f32> = expect.iter().map(|&i| keys[i as usize]).collect();
            prop_assert_eq!(got, want);
        }
    }
    /// Keys with many duplicates, both zeros and negatives: what trips sorts up.
    fn awkward_keys() -> impl Strategy<Value = Vec<f32>> {
        proptest::collection::vec(
            prop_oneof![
                -1e6f32..1e6,
                (-4i32..4).prop_map(|i| i as f32 * 0.5),
                Just(0.0f32),
                Just(-0.0f32),
                Just(f32::MAX),
                Just(f32::MIN),
            ],
            0..3000,
        )
    }

    /// The stable ascending order by `total_cmp` (the reference).
    fn stable_order(keys: &[f32]) -> Vec<u32> {
        let mut expect: Vec<u32> = (0..keys.len() as u32).collect();
        expect.sort_by(|&i, &j| keys[i as usize].total_cmp(&keys[j as usize]));
        expect
    }

    fn is_permutation(idx: &[u32], n: usize) -> bool {
        let mut seen = vec![false; n];
        idx.len() == n
            && idx
                .iter()
                .all(|&i| (i as usize) < n && !std::mem::replace(&mut seen[i as usize], true))
    }

    proptest! {
        #[test]
        fn classic_sorts_give_the_stable_order(keys in awkward_keys()) {
            let expect = stable_order(&keys);
            for s in [CpuSort::Shell, CpuSort::Heap, CpuSort::Quick, CpuSort::Radix, CpuSort::Merge] {
                let mut idx = vec![7];
                s.sort_indices(&keys, &mut idx);
                prop_assert_eq!(&idx, &expect, "{}", s.name());
            }
            // The standard library's sort is unstable: same keys in the same order.
            let mut idx = Vec::new();
            std_sort_indices(&keys, &mut idx);
            prop_assert!(is_permutation(&idx, keys.len()));
            let got: Vec<u32> = idx.iter().map(|&i| float_to_ordered_u32(keys[i as usize])).collect();
            let want: Vec<u32> = expect.iter().map(|&i| float_to_ordered_u32(keys[i as usize])).collect();
            prop_assert_eq!(got, want);
        }

        #[test]
        fn radix_variants_give_the_stable_order(keys in awkward_keys()) {
            let mut scratch = RadixScratch::default();
            let mut idx = Vec::new();
            radix_sort_packed::<11>(&keys, 0, &mut idx, &mut scratch);
            prop_assert_eq!(&idx, &stable_order(&keys));
            let mut expect: Vec<u32> = (0..keys.len() as u32).collect();
            expect.sort_by(|&i, &j| keys[j as usize].total_cmp(&keys[i as usize]));
            radix_sort_indices_descending(&keys, &mut idx, &mut scratch);
            prop_assert_eq!(&idx, &expect);
        }

        #[test]
        fn parallel_radix_gives_the_stable_order(keys in awkward_keys()) {
            let mut scratch = RadixScratch::default();
            let mut idx = Vec::new();
            radix_sort_indices_parallel(&keys, &mut idx, &mut scratch);
            prop_assert_eq!(&idx, &stable_order(&keys));
        }

        #[test]
        fn merge_sort_descending_is_stable(keys in awkward_keys()) {
            let mut expect: Vec<u32> = (0..keys.len() as u32).collect();
            expect.sort_by(|&i, &j| keys[j as usize].total_cmp(&keys[i as usize]));
            let mut idx = Vec::new();
            merge_sort_indices(&keys, true, &mut idx, &mut Vec::new());
            prop_assert_eq!(idx, expect);
        }

        #[test]
        fn generic_sorts_sort_plain_floats(mut v in proptest::collection::vec(-1e3f32..1e3, 0..500)) {
            let mut want = v.clone();
            want.sort_by(f32::total_cmp);
            let mut a = v.clone();
            shellsort(&mut a, |x, y| x < y);
            let mut b = v.clone();
            heapsort(&mut b, |x, y| x < y);
            let mut c = v.clone();
            quicksort(&mut c, |x, y| x < y);
            merge_sort(&mut v, &mut Vec::new(), |x, y| x < y);
            prop_assert_eq!(&a, &want);
            prop_assert_eq!(&b, &want);
            prop_assert_eq!(&c, &want);
            prop_assert_eq!(&v, &want);
        }

        /// Bucket sort: a permutation whose slabs are in order; inside a slab the input order.
        #[test]
        fn bucket_sort_orders_slabs(keys in proptest::collection::vec(-50f32..50.0, 0..3000),
                                    slabs in 1usize..40, descending: bool) {
            let mut idx = Vec::new();
            let (lo, hi) = bucket_sort_indices(&keys, slabs, descending, &mut idx);
            prop_assert!(is_permutation(&idx, keys.len()));
            let slab: Vec<usize> = idx.iter().map(|&i| slab_of(keys[i as usize], lo, hi, slabs)).collect();
            for w in 0..idx.len().saturating_sub(1) {
                let (a, b) = (slab[w], slab[w + 1]);
                if descending { prop_assert!(a >= b); } else { prop_assert!(a <= b); }
                if a == b { prop_assert!(idx[w] < idx[w + 1], "order inside a slab is the input order"); }
                // Keys of a later slab are never on the wrong side of an earlier slab's keys.
                let (ka, kb) = (keys[idx[w] as usize], keys[idx[w + 1] as usize]);
                let in_order = if descending { ka > kb } else { ka < kb };
                if a != b { prop_assert!(in_order); }
            }
        }
    }

    /// Large enough for several parts per thread: the parallel sort (both directions, through
    /// the dispatching entry points) gives exactly the serial permutation, duplicates included.
    #[test]
    fn parallel_radix_equals_serial_on_large_inputs() {
        let mut s = 0x2545_F491_4F6C_DD1Du64;
        let keys: Vec<f32> = (0..300_000)
            .map(|i| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                match i % 5 {
                    0 => ((s >> 40) % 64) as f32 - 32.0, // many duplicates, negatives
                    1 => -0.0,
                    _ => (s >> 40) as f32 / 1e3 - 8e3,
                }
            })
            .collect();
        let (mut serial, mut parallel) = (Vec::new(), Vec::new());
        let mut scratch = RadixScratch::default();
        radix_sort_indices_serial(&keys, &mut serial, &mut scratch);
        assert_eq!(serial, stable_order(&keys));
        radix_sort_indices_parallel(&keys, &mut parallel, &mut scratch);
        assert_eq!(parallel, serial);
        radix_sort_indices(&keys, &mut parallel, &mut scratch);
        assert_eq!(parallel, serial);
        let mut expect: Vec<u32> = (0..keys.len() as u32).collect();
        expect.sort_by(|&i, &j| keys[j as usize].total_cmp(&keys[i as usize]));
        radix_sort_indices_descending(&keys, &mut parallel, &mut scratch);
        assert_eq!(parallel, expect);
    }

    #[test]
    fn sorts_handle_tiny_inputs() {
        for keys in [vec![], vec![1.0f32], vec![2.0, 1.0], vec![1.0, 1.0, 1.0]] {
            let expect = stable_order(&keys);
            for s in CpuSort::TABLE1.into_iter().chain([CpuSort::Merge]) {
                let mut idx = Vec::new();
                s.sort_indices(&keys, &mut idx);
                assert!(is_permutation(&idx, keys.len()));
                if s != CpuSort::Std {
                    assert_eq!(idx, expect, "{}", s.name());
                }
            }
            let mut idx = Vec::new();
            bucket_sort_indices(&keys, DEFAULT_SLABS, true, &mut idx);
            assert!(is_permutation(&idx, keys.len()));
        }
    }
}
