//! Sorting 1 M uniformly random f32 keys with an index payload (HAVS Table 1, and the radix-sort
//! criterion of the measurement-core issue: ≥ 150 M keys/s and ≥ 5× `sort_unstable_by`).
//! Criterion reports throughput in keys/s (`Throughput::Elements`).
//!
//! `cargo bench -p render-core --bench sort`

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use render_core::sort::{
    bucket_sort_indices, heapsort_indices, merge_sort_indices, quicksort_indices,
    radix_sort_indices, radix_sort_packed, shellsort_indices, std_sort_indices, RadixScratch,
    DEFAULT_SLABS,
};

const N: usize = 1 << 20;

/// Uniform random keys in [0, 1) from a fixed-seed xorshift (reproducible, no dependency).
fn random_keys(n: usize) -> Vec<f32> {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32
        })
        .collect()
}

fn bench_sorts(c: &mut Criterion) {
    let keys = random_keys(N);
    let mut g = c.benchmark_group("sort_1M_f32");
    g.throughput(Throughput::Elements(N as u64));
    g.sample_size(10);

    let mut scratch = RadixScratch::default();
    let mut out = Vec::with_capacity(N);
    g.bench_function("radix", |b| {
        b.iter(|| radix_sort_indices(&keys, &mut out, &mut scratch))
    });
    // Three 11-bit passes instead of four 8-bit ones (the alternative the issue suggests).
    g.bench_function("radix_11bit", |b| {
        b.iter(|| radix_sort_packed::<11>(&keys, 0, &mut out, &mut scratch))
    });
    g.bench_function("std_sort_unstable_by", |b| {
        b.iter(|| std_sort_indices(&keys, &mut out))
    });
    // What a renderer often writes instead: sorting the index array through the keys.
    g.bench_function("std_sort_unstable_by_indirect", |b| {
        b.iter_batched_ref(
            || (0..N as u32).collect::<Vec<u32>>(),
            |idx| idx.sort_unstable_by(|&i, &j| keys[i as usize].total_cmp(&keys[j as usize])),
            BatchSize::LargeInput,
        )
    });
    g.bench_function("shellsort", |b| {
        b.iter(|| shellsort_indices(&keys, &mut out))
    });
    g.bench_function("heapsort", |b| b.iter(|| heapsort_indices(&keys, &mut out)));
    g.bench_function("quicksort", |b| {
        b.iter(|| quicksort_indices(&keys, &mut out))
    });
    let mut merge_scratch = Vec::new();
    g.bench_function("merge", |b| {
        b.iter(|| merge_sort_indices(&keys, false, &mut out, &mut merge_scratch))
    });
    g.bench_function("bucket20", |b| {
        b.iter(|| bucket_sort_indices(&keys, DEFAULT_SLABS, false, &mut out))
    });
    g.finish();
}

criterion_group!(benches, bench_sorts);
criterion_main!(benches);
