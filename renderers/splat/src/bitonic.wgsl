// One compare-exchange stage (k, j) of a bitonic sort of (key, value) pairs over a power-of-two
// length, ascending by (key, value) so that the order equals a stable sort of the keys
// (values are the original indices). Grau & Tost §3.4 sort with Govindaraju et al.'s GPU
// bitonic network; this is the same network in a compute shader.

struct Stage {
    k: u32,
    j: u32,
    n: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> st: Stage;
@group(0) @binding(1) var<storage, read_write> keys: array<f32>;
@group(0) @binding(2) var<storage, read_write> vals: array<u32>;

@compute @workgroup_size(256)
fn bitonic_stage(@builtin(global_invocation_id) g: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = g.x + g.y * nwg.x * 256u;
    if (i >= st.n) {
        return;
    }
    let l = i ^ st.j;
    if (l <= i) {
        return;
    }
    let ki = keys[i];
    let kl = keys[l];
    let vi = vals[i];
    let vl = vals[l];
    let ascending = (i & st.k) == 0u;
    let greater = ki > kl || (ki == kl && vi > vl);
    if (greater == ascending) {
        keys[i] = kl;
        keys[l] = ki;
        vals[i] = vl;
        vals[l] = vi;
    }
}
