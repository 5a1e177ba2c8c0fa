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
/// u32 images of the keys: 4 passes of 8 bits, stable. `scratch` is reused between frames.
pub fn radix_sort_indices(keys: &[f32], indices: &mut Vec<u32>, scratch: &mut RadixScratch) {
    let n = keys.len();
    scratch.keys_a.clear();
    scratch.keys_a.extend(keys.iter().map(|&k| float_to_ordered_u32(k)));
    scratch.vals_a.clear();
    scratch.vals_a.extend(0..n as u32);
    scratch.keys_b.resize(n, 0);
    scratch.vals_b.resize(n, 0);
    // One read of the keys builds all four histograms.
    let mut hist = [[0u32; 256]; 4];
    for &k in &scratch.keys_a {
        for (p, h) in hist.iter_mut().enumerate() {
            h[((k >> (8 * p)) & 0xff) as usize] += 1;
        }
    }
    let (mut ka, mut kb) = (&mut scratch.keys_a, &mut scratch.keys_b);
    let (mut va, mut vb) = (&mut scratch.vals_a, &mut scratch.vals_b);
    for (pass, h) in hist.iter().enumerate() {
        // A pass where every key has the same digit changes nothing: skip it.
        if h.iter().any(|&c| c as usize == n) {
            continue;
        }
        let mut offset = [0u32; 256];
        let mut sum = 0;
        for d in 0..256 {
            offset[d] = sum;
            sum += h[d];
        }
        let shift = 8 * pass;
        for i in 0..n {
            let k = ka[i];
            let d = ((k >> shift) & 0xff) as usize;
            let o = offset[d] as usize;
            offset[d] += 1;
            kb[o] = k;
            vb[o] = va[i];
        }
        std::mem::swap(&mut ka, &mut kb);
        std::mem::swap(&mut va, &mut vb);
    }
    indices.clear();
    indices.extend_from_slice(va);
}

/// Buffers the radix sort reuses from frame to frame.
#[derive(Debug, Default, Clone)]
pub struct RadixScratch {
    keys_a: Vec<u32>,
    keys_b: Vec<u32>,
    vals_a: Vec<u32>,
    vals_b: Vec<u32>,
}

/// Back-to-front order: indices sorted by descending key.
pub fn radix_sort_indices_descending(keys: &[f32], indices: &mut Vec<u32>, scratch: &mut RadixScratch) {
    radix_sort_indices(keys, indices, scratch);
    indices.reverse();
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
}
