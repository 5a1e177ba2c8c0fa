//! The sorts against the standard library's order, on awkward and random keys.

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
