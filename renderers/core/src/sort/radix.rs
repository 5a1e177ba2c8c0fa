//! The LSD radix sort of HAVS §5.1 over the ordered u32 images of f32 keys, serial and split
//! over rayon's threads.

use super::float_to_ordered_u32;

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
