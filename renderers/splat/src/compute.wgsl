// Per-brick GPU bucket construction (Grau & Tost §3.3-3.5): view transform -> (sort, in
// bitonic.wgsl or render-core's radix sort) -> gather into depth order -> bucket boundaries.

@group(0) @binding(0) var<storage, read> fr: Frame;
@group(0) @binding(1) var<storage, read> voxels: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> keys: array<f32>;
@group(0) @binding(3) var<storage, read_write> vals: array<u32>;
@group(0) @binding(4) var<storage, read_write> sorted: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> ends: array<u32>;

fn flat_id(g: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return g.x + g.y * nwg.x * 256u;
}

// §3.3: key = view depth, value = voxel index. Entries past n (bitonic padding to a power
// of two) get +inf keys so they sort last.
@compute @workgroup_size(256)
fn transform(@builtin(global_invocation_id) g: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = flat_id(g, nwg);
    if (i >= fr.padded) {
        return;
    }
    if (i < fr.n) {
        keys[i] = view_depth(fr, voxels[i].xyz);
        vals[i] = i;
    } else {
        keys[i] = bitcast<f32>(0x7f800000u);
        vals[i] = 0xffffffffu;
    }
}

// The Depth-Sorted Voxels array the splat pass reads.
@compute @workgroup_size(256)
fn gather(@builtin(global_invocation_id) g: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = flat_id(g, nwg);
    if (i >= fr.n) {
        return;
    }
    sorted[i] = voxels[vals[i]];
}

fn slab_of(d: f32) -> u32 {
    let s = floor((d - fr.d0) * fr.inv_delta);
    return min(u32(max(s, 0.0)), fr.num_slabs - 1u);
}

// §3.5: voxel i is a bucket boundary when voxel i + 1 lies in a later slab; it then ends the
// buckets slab(i) ... slab(i+1) - 1 (empty slabs between included), so every entry of the
// table is written by exactly one thread, without atomics. Thread 0 also zeroes the slabs
// before the first voxel. (The paper does this with a flag texture and an early depth test;
// a compute pass is the direct equivalent.)
@compute @workgroup_size(256)
fn boundaries(@builtin(global_invocation_id) g: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = flat_id(g, nwg);
    if (i >= fr.n) {
        return;
    }
    let s = slab_of(keys[i]);
    if (i == 0u) {
        for (var k = 0u; k < s; k++) {
            ends[k] = 0u;
        }
    }
    var next = fr.num_slabs;
    if (i + 1u < fr.n) {
        next = slab_of(keys[i + 1u]);
    }
    for (var k = s; k < next; k++) {
        ends[k] = i + 1u;
    }
}
