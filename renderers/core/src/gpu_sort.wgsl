// LSD radix sort of (key, value) u32 pairs on the GPU: four passes of 8 bits, each made of
//   histogram   – per-workgroup (tile) digit counts,
//   scan_tiles  – per digit, the exclusive prefix over tiles, and the digit's total: one
//                 workgroup a digit scanning its tiles in parallel (a GPU's choice), or
//   scan_digits – the same prefixes and totals from one workgroup, each invocation a digit
//                 walking the tiles in order (a CPU backend's: it runs a workgroup on one core
//                 and each barrier as a switch through all its invocations, so scan_tiles's 256
//                 workgroups of 16 barriers were a fixed 12.5 ms a sort on lavapipe),
//   scatter     – a stable scatter: tiles in order, and inside a tile sub-blocks of 256 keys in
//                 order, each key ranked among the equal digits of lower threads of its
//                 sub-block through per-digit thread bitsets (the "match" of Onesweep-style
//                 sorts, done with workgroup atomics because subgroup ballots are not portable).
// Keys arrive as f32 bits and are mapped to ordered u32 in the first pass (HAVS §5.1: flip the
// sign bit of positives, all bits of negatives; complemented again for a descending sort); the
// last pass maps them back, so the caller's key buffer ends sorted as f32.

struct Params {
    n: u32,
    shift: u32,
    num_tiles: u32,
    // bit 0: keys_in hold f32 bits (map them); bit 1: descending; bit 2: unmap keys on output.
    flags: u32,
}

const WG: u32 = 256u;
// Sub-blocks of WG keys per tile; a tile is TILE = WG * SUB keys (keep in sync with the Rust).
const SUB: u32 = 16u;
const TILE: u32 = 4096u;

const MAP_IN: u32 = 1u;
const DESCENDING: u32 = 2u;
const UNMAP_OUT: u32 = 4u;

@group(0) @binding(0) var<storage, read> params: Params;
// keys_in, vals_in, keys_out, vals_out: declared by the Rust (gpu_sort.rs, `sort_source`) at
// bindings 10.., each split over as many storage bindings as the sorter's capacity needs, and
// read and written through keys_in_at(i), keys_out_set(i, v), ...
// tile_hist[digit * num_tiles + tile]: counts, then (after scan_tiles) exclusive prefixes.
@group(0) @binding(5) var<storage, read_write> tile_hist: array<u32>;
@group(0) @binding(6) var<storage, read_write> digit_total: array<u32>;

fn ordered(bits: u32) -> u32 {
    if (bits & 0x80000000u) != 0u {
        return ~bits;
    }
    return bits | 0x80000000u;
}

fn unordered(u: u32) -> u32 {
    if (u & 0x80000000u) != 0u {
        return u ^ 0x80000000u;
    }
    return ~u;
}

fn load_key(i: u32) -> u32 {
    var k = keys_in_at(i);
    if (params.flags & MAP_IN) != 0u {
        k = ordered(k);
        if (params.flags & DESCENDING) != 0u {
            k = ~k;
        }
    }
    return k;
}

fn store_key(k: u32) -> u32 {
    if (params.flags & UNMAP_OUT) != 0u {
        var u = k;
        if (params.flags & DESCENDING) != 0u {
            u = ~u;
        }
        return unordered(u);
    }
    return k;
}

var<workgroup> wg_hist: array<atomic<u32>, 256>;
var<workgroup> scan_buf: array<u32, 256>;
// match_mask[d][w]: bit b set when thread 32 w + b of the current sub-block has digit d.
var<workgroup> match_mask: array<array<atomic<u32>, 8>, 256>;
var<workgroup> running: array<u32, 256>;
// Keys of each digit in the current sub-block (scatter).
var<workgroup> sub_count: array<atomic<u32>, 256>;

// Inclusive Hillis–Steele scan over the workgroup (must be called in uniform control flow).
fn workgroup_inclusive_scan(lid: u32, v: u32) -> u32 {
    scan_buf[lid] = v;
    workgroupBarrier();
    var x = v;
    for (var off = 1u; off < WG; off = off << 1u) {
        var y = 0u;
        if lid >= off {
            y = scan_buf[lid - off];
        }
        workgroupBarrier();
        x = x + y;
        scan_buf[lid] = x;
        workgroupBarrier();
    }
    return x;
}

@compute @workgroup_size(256)
fn histogram(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    atomicStore(&wg_hist[lid], 0u);
    workgroupBarrier();
    let tile = wid.x;
    for (var s = 0u; s < SUB; s = s + 1u) {
        let i = tile * TILE + s * WG + lid;
        if i < params.n {
            let d = (load_key(i) >> params.shift) & 0xffu;
            atomicAdd(&wg_hist[d], 1u);
        }
    }
    workgroupBarrier();
    tile_hist[lid * params.num_tiles + tile] = atomicLoad(&wg_hist[lid]);
}

// One workgroup per digit: exclusive prefix of the digit's tile counts, and its total.
@compute @workgroup_size(256)
fn scan_tiles(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let row = wid.x * params.num_tiles;
    let chunks = (params.num_tiles + WG - 1u) / WG;
    var carry = 0u;
    for (var c = 0u; c < chunks; c = c + 1u) {
        let t = c * WG + lid;
        var v = 0u;
        if t < params.num_tiles {
            v = tile_hist[row + t];
        }
        let inc = workgroup_inclusive_scan(lid, v);
        if t < params.num_tiles {
            tile_hist[row + t] = carry + inc - v;
        }
        carry = carry + scan_buf[WG - 1u];
        workgroupBarrier();
    }
    if lid == 0u {
        digit_total[wid.x] = carry;
    }
}

// One workgroup, invocation `lid` = digit: what scan_tiles computes, each digit's row of tile
// counts walked in order (the row is contiguous, tile_hist[digit * num_tiles + tile]).
@compute @workgroup_size(256)
fn scan_digits(@builtin(local_invocation_index) lid: u32) {
    let row = lid * params.num_tiles;
    var sum = 0u;
    for (var t = 0u; t < params.num_tiles; t = t + 1u) {
        let c = tile_hist[row + t];
        tile_hist[row + t] = sum;
        sum = sum + c;
    }
    digit_total[lid] = sum;
}

@compute @workgroup_size(256)
fn scatter(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let tile = wid.x;
    // Where digit `lid` starts: all smaller digits, plus this digit in earlier tiles.
    let total = digit_total[lid];
    let inc = workgroup_inclusive_scan(lid, total);
    running[lid] = inc - total + tile_hist[lid * params.num_tiles + tile];
    // The bitsets start empty; each key clears its own bit after its sub-block, so they are
    // empty again at the next (one atomic a key instead of eight stores an invocation).
    for (var w = 0u; w < 8u; w = w + 1u) {
        atomicStore(&match_mask[lid][w], 0u);
    }
    atomicStore(&sub_count[lid], 0u);
    let word = lid >> 5u;
    let bit = 1u << (lid & 31u);
    for (var s = 0u; s < SUB; s = s + 1u) {
        workgroupBarrier();
        let i = tile * TILE + s * WG + lid;
        let valid = i < params.n;
        var key = 0u;
        var d = 0u;
        if valid {
            key = load_key(i);
            d = (key >> params.shift) & 0xffu;
            atomicOr(&match_mask[d][word], bit);
        }
        workgroupBarrier();
        if valid {
            // Rank among the keys of this sub-block with the same digit and a lower thread id.
            var rank = countOneBits(atomicLoad(&match_mask[d][word]) & (bit - 1u));
            for (var w = 0u; w < word; w = w + 1u) {
                rank = rank + countOneBits(atomicLoad(&match_mask[d][w]));
            }
            let dst = running[d] + rank;
            keys_out_set(dst, store_key(key));
            vals_out_set(dst, vals_in_at(i));
            // The digit's count in the sub-block is its highest rank + 1.
            atomicMax(&sub_count[d], rank + 1u);
        }
        workgroupBarrier();
        if valid {
            atomicAnd(&match_mask[d][word], ~bit);
        }
        running[lid] = running[lid] + atomicExchange(&sub_count[lid], 0u);
    }
}

// ---------------------------------------------------------------------------------------------
// Sort keys computed on the GPU: for primitive p (a tet of 4 or a face of 3 vertex indices), key
// = the visibility-sort distance of its centroid (Camera::sort_distance: distance from the eye
// in perspective, depth along the view axis in orthographic projection), value = p. Callers that
// sort on the device run this, then GpuRadixSort::encode, then draw, with no readback.
// Group 1 so that its bindings never meet the sort's in one pipeline layout.

struct KeyParams {
    eye: vec3<f32>,
    // 1: perspective (distance to `eye`), 0: orthographic (depth along `forward`).
    perspective: u32,
    forward: vec3<f32>,
    count: u32,
    // floats per point (3 for xyz, 4 for xyz + scalar)
    point_stride: u32,
    // vertex indices per primitive (3 or 4)
    verts: u32,
    // Added to the primitive index written as the value (chunked callers).
    value_base: u32,
    // Where primitive 0 of this call is written in key_out and value_out (a caller whose
    // primitives are split over several buffers writes each buffer's keys at its place).
    out_base: u32,
}

@group(1) @binding(0) var<storage, read> kp: KeyParams;
@group(1) @binding(1) var<storage, read> key_points: array<f32>;
@group(1) @binding(2) var<storage, read> key_prims: array<u32>;
@group(1) @binding(3) var<storage, read_write> key_out: array<f32>;
@group(1) @binding(4) var<storage, read_write> value_out: array<u32>;

@compute @workgroup_size(256)
fn centroid_keys(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let p = gid.x + gid.y * nwg.x * 256u;
    if p >= kp.count {
        return;
    }
    var c = vec3<f32>(0.0);
    for (var v = 0u; v < kp.verts; v = v + 1u) {
        let i = key_prims[p * kp.verts + v] * kp.point_stride;
        c = c + vec3<f32>(key_points[i], key_points[i + 1u], key_points[i + 2u]);
    }
    c = c / f32(kp.verts);
    let d = c - kp.eye;
    var key = dot(d, kp.forward);
    if kp.perspective != 0u {
        key = length(d);
    }
    key_out[kp.out_base + p] = key;
    value_out[kp.out_base + p] = kp.value_base + p;
}
