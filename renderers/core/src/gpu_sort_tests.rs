//! Tests of the GPU radix sort and key pass (gpu_sort.rs) against the CPU sorts.

use super::*;
use crate::sort::{radix_sort_indices, radix_sort_indices_descending, RadixScratch};

fn xorshift_keys(n: usize, seed: u64) -> Vec<f32> {
    let mut s = seed | 1;
    (0..n)
        .map(|i| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            match i % 7 {
                // duplicates, both zeros, and negative keys mixed in
                0 => ((s >> 60) as f32) - 8.0,
                1 => {
                    if s & 1 == 0 {
                        0.0
                    } else {
                        -0.0
                    }
                }
                _ => ((s >> 11) as f64 / (1u64 << 53) as f64 * 2e4 - 1e4) as f32,
            }
        })
        .collect()
}

/// The GPU sort equals the CPU radix sort exactly (both are stable LSD sorts on the same
/// ordered-u32 images), for sizes around and off the tile size, ascending and descending,
/// with either way of scanning the tiles (the adapter's own and the other).
#[test]
fn gpu_radix_sort_agrees_with_cpu() {
    let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
    let mut scratch = RadixScratch::default();
    for tile_scan in [TileScan::PerDigit, TileScan::Serial] {
        let sorter = GpuRadixSort::new(&gpu, 100_000, &mut MemoryLedger::default())
            .unwrap()
            .with_tile_scan(tile_scan);
        for (n, seed) in [
            (0usize, 1u64),
            (1, 2),
            (255, 3),
            (4096, 4),
            (4097, 5),
            (33_333, 6),
            (100_000, 7),
        ] {
            let keys = xorshift_keys(n, seed);
            for descending in [false, true] {
                let (sorted, perm) = sorter.sort_pairs_blocking(&gpu, &keys, descending).unwrap();
                let mut want = Vec::new();
                if descending {
                    radix_sort_indices_descending(&keys, &mut want, &mut scratch);
                } else {
                    radix_sort_indices(&keys, &mut want, &mut scratch);
                }
                let case = format!("n = {n}, descending = {descending}, {tile_scan:?}");
                assert_eq!(perm, want, "{case}");
                let want_keys: Vec<u32> =
                    want.iter().map(|&i| keys[i as usize].to_bits()).collect();
                let got_keys: Vec<u32> = sorted.iter().map(|k| k.to_bits()).collect();
                assert_eq!(
                    got_keys, want_keys,
                    "{case}: keys come back sorted, bit for bit"
                );
            }
        }
    }
    let expected = if gpu.adapter.is_cpu() {
        TileScan::Serial
    } else {
        TileScan::PerDigit
    };
    assert_eq!(TileScan::for_adapter(&gpu), expected);
    assert_eq!(
        sort_blocking(&gpu, &[3.0, -1.0, 2.0]).unwrap(),
        vec![1, 2, 0]
    );
}

/// Usage of the key-pass tests' buffers: what the sort needs, and read back.
fn test_usage() -> wgpu::BufferUsages {
    REQUIRED_USAGE | wgpu::BufferUsages::COPY_SRC
}

/// `data` in a persistent buffer, as a key pass reads points and primitives.
fn upload<T: bytemuck::Pod>(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    label: &str,
    data: &[T],
) -> anyhow::Result<wgpu::Buffer> {
    let bytes = bytemuck::cast_slice(data);
    ledger.buffer_init(gpu, label, Lifetime::Persistent, bytes, test_usage())
}

/// A per-frame array of `n` keys or ids.
fn per_element(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    label: &str,
    n: u32,
) -> anyhow::Result<wgpu::Buffer> {
    ledger.buffer(gpu, label, Lifetime::PerFrame, n as u64 * 4, test_usage())
}

/// A lattice of `dims` points (xyz; `w` in the fourth lane), its tets and its bounds: the
/// mesh of the key-pass tests.
fn lattice(dims: [usize; 3], w: f32) -> (Vec<[f32; 4]>, Vec<[u32; 4]>, datasets::Aabb) {
    let mut pts = Vec::new();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                pts.push([i as f32 * 0.3, j as f32 * 0.5 - 1.0, k as f32 * 0.4, w]);
            }
        }
    }
    let bounds =
        datasets::Aabb::of_points(&pts.iter().map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>());
    (pts, datasets::volume::structured_tets(dims), bounds)
}

/// Keys computed on the GPU match the CPU's centroid distances, and key pass + sort give
/// the CPU's back-to-front centroid order (up to near-ties of f32 rounding).
#[test]
fn gpu_centroid_keys_then_sort_match_the_cpu() -> anyhow::Result<()> {
    use crate::scene::{fixed_viewpoints, Camera, Projection};
    let gpu = Gpu::new().expect("a wgpu adapter");
    let (pts, tets, bounds) = lattice([9, 8, 7], 7.0);
    let n = tets.len() as u32;
    let mut ledger = MemoryLedger::default();
    let pbuf = upload(&gpu, &mut ledger, "points", &pts)?;
    let tbuf = upload(&gpu, &mut ledger, "tets", &tets)?;
    let kbuf = per_element(&gpu, &mut ledger, "keys", n)?;
    let vbuf = per_element(&gpu, &mut ledger, "values", n)?;
    let keys_pass = GpuCentroidKeys::new(&gpu, &mut ledger).unwrap();
    let sorter = GpuRadixSort::new(&gpu, n, &mut ledger).unwrap();
    for (vi, vp) in fixed_viewpoints().iter().enumerate().step_by(3) {
        let proj = if vi % 2 == 0 {
            Projection::default()
        } else {
            Projection::Orthographic
        };
        let cam = Camera::fit(&bounds, vp, proj, 64, 64);
        let cpu_keys: Vec<f32> = tets
            .iter()
            .map(|t| {
                let c = [0, 1, 2]
                    .map(|a| t.iter().map(|&v| pts[v as usize][a] as f64).sum::<f64>() / 4.0);
                cam.sort_distance(c) as f32
            })
            .collect();
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        keys_pass
            .encode(&mut enc, &cam, &pbuf, 4, &tbuf, 4, n, 0, &kbuf, &vbuf)
            .unwrap();
        gpu.queue.submit([enc.finish()]);
        let gk: Vec<f32> =
            bytemuck::cast_slice(&gpu.read_buffer(&kbuf, 0, n as u64 * 4).unwrap()).to_vec();
        let scale = cam.far;
        for (g, c) in gk.iter().zip(&cpu_keys) {
            assert!(
                ((g - c) as f64).abs() <= 1e-5 * scale,
                "GPU key {g} vs CPU {c}"
            );
        }
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        keys_pass
            .encode(&mut enc, &cam, &pbuf, 4, &tbuf, 4, n, 0, &kbuf, &vbuf)
            .unwrap();
        sorter.encode(&mut enc, &kbuf, &vbuf, n, true).unwrap();
        gpu.queue.submit([enc.finish()]);
        let order: Vec<u32> =
            bytemuck::cast_slice(&gpu.read_buffer(&vbuf, 0, n as u64 * 4).unwrap()).to_vec();
        let mut seen = order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..n).collect::<Vec<_>>());
        // Back to front by the CPU keys, up to ties within the f32 rounding of the keys.
        for w in order.windows(2) {
            let (a, b) = (
                cpu_keys[w[0] as usize] as f64,
                cpu_keys[w[1] as usize] as f64,
            );
            assert!(a >= b - 2e-5 * scale, "{a} before {b}");
        }
    }
    Ok(())
}

/// A key pass over primitives split over several buffers (GATOR's tet chunks) writes, in
/// one submission, the keys and ids one call over the whole array writes, bit for bit; one
/// call more than the instance holds is refused.
#[test]
fn a_key_pass_over_split_primitives_equals_one_over_the_whole() -> anyhow::Result<()> {
    use crate::scene::{Camera, Projection, Viewpoint};
    let gpu = Gpu::new().expect("a wgpu adapter");
    let (pts, tets, bounds) = lattice([7, 6, 5], 1.0);
    let n = tets.len() as u32;
    let mut ledger = MemoryLedger::default();
    let pbuf = upload(&gpu, &mut ledger, "points", &pts)?;
    let whole = upload(&gpu, &mut ledger, "tets", &tets)?;
    // Three pieces of unequal length, as a caller's chunks of one storage binding each.
    let cuts = [0, 100, 333, n as usize];
    let pieces: Vec<wgpu::Buffer> = cuts
        .windows(2)
        .map(|w| upload(&gpu, &mut ledger, "tet piece", &tets[w[0]..w[1]]))
        .collect::<anyhow::Result<_>>()?;
    let ranges: Vec<KeyRange> = pieces
        .iter()
        .zip(cuts.windows(2))
        .map(|(prims, w)| KeyRange {
            prims,
            first: w[0] as u32,
            count: (w[1] - w[0]) as u32,
        })
        .collect();
    let (k1, v1, k3, v3) = (
        per_element(&gpu, &mut ledger, "k1", n)?,
        per_element(&gpu, &mut ledger, "v1", n)?,
        per_element(&gpu, &mut ledger, "k3", n)?,
        per_element(&gpu, &mut ledger, "v3", n)?,
    );
    let one = GpuCentroidKeys::new(&gpu, &mut ledger)?;
    let three = GpuCentroidKeys::with_calls(&gpu, 3, &mut ledger)?;
    assert_eq!(three.max_calls(), 3);
    for proj in [Projection::default(), Projection::Orthographic] {
        let cam = Camera::fit(
            &bounds,
            &Viewpoint::new("oblique", [0.3, -0.6, 0.7]),
            proj,
            64,
            64,
        );
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        one.encode(&mut enc, &cam, &pbuf, 4, &whole, 4, n, 0, &k1, &v1)?;
        three.encode_ranges(&mut enc, &cam, &pbuf, 4, 4, &ranges, &k3, &v3)?;
        gpu.queue.submit([enc.finish()]);
        let read = |b: &wgpu::Buffer| gpu.read_buffer(b, 0, n as u64 * 4).unwrap();
        assert_eq!(read(&k1), read(&k3), "{proj:?}: keys");
        assert_eq!(read(&v1), read(&v3), "{proj:?}: ids");
        let ids: Vec<u32> = bytemuck::cast_slice(&read(&v3)).to_vec();
        assert_eq!(ids, (0..n).collect::<Vec<_>>());
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        let e = one
            .encode_ranges(&mut enc, &cam, &pbuf, 4, 4, &ranges, &k3, &v3)
            .unwrap_err()
            .to_string();
        assert!(e.contains("3 calls") && e.contains("holds 1"), "{e}");
    }
    Ok(())
}

/// Arrays larger than one storage binding sort in one piece (HAVS's 20 M-tet
/// faces): with the binding limited to 256 KiB (65,536 keys), 65,537 and 150,000 keys span
/// two and three bindings, and the order equals the CPU radix sort's exactly, ascending
/// and descending; a sort of fewer keys than the sorter holds binds its unused chunks
/// harmlessly.
#[test]
fn a_sort_larger_than_one_binding_agrees_with_cpu() {
    let gpu = Gpu::with_request(&crate::DeviceRequest {
        max_storage_binding: Some(256 << 10),
        ..Default::default()
    })
    .expect("a wgpu adapter");
    assert_eq!(gpu.max_storage_binding(), 256 << 10);
    let sorter = GpuRadixSort::new(&gpu, 150_000, &mut MemoryLedger::default()).unwrap();
    assert_eq!(sorter.bindings_per_array(), 3);
    let mut scratch = RadixScratch::default();
    for (n, seed) in [(1000usize, 8u64), (65_537, 9), (150_000, 10)] {
        let keys = xorshift_keys(n, seed);
        for descending in [false, true] {
            let (sorted, perm) = sorter.sort_pairs_blocking(&gpu, &keys, descending).unwrap();
            let mut want = Vec::new();
            if descending {
                radix_sort_indices_descending(&keys, &mut want, &mut scratch);
            } else {
                radix_sort_indices(&keys, &mut want, &mut scratch);
            }
            assert_eq!(perm, want, "n = {n}, descending = {descending}");
            let want_keys: Vec<u32> = want.iter().map(|&i| keys[i as usize].to_bits()).collect();
            let got_keys: Vec<u32> = sorted.iter().map(|k| k.to_bits()).collect();
            assert_eq!(got_keys, want_keys, "n = {n}: keys come back sorted");
        }
    }
}
