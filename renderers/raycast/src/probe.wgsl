// Test entry: one ray step (exit face, next tet, exit λ and scalar) for arbitrary rays, so the
// CPU twin (step.rs) can be compared with the shader's arithmetic.

struct ProbeIn {
    o: vec4<f32>,     // xyz, λ at entry
    d: vec4<f32>,     // xyz, unused
    tet: vec4<u32>,   // binding, index, unused, unused
}

@group(1) @binding(0) var<storage, read> probes: array<ProbeIn>;
// face, next binding, next index, λ exit bits; s exit bits, unused ×3
@group(1) @binding(1) var<storage, read_write> probe_out: array<vec4<u32>>;

@compute @workgroup_size(64)
fn probe(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x;
    if k >= arrayLength(&probes) {
        return;
    }
    let q = probes[k];
    let ex = exit_of(q.tet.xy, q.o.xyz, q.d.xyz, q.o.w);
    let face = ex.face;
    let next = ex.next;
    let lambda_exit = ex.lambda;
    let s_exit = ex.s;
    probe_out[2u * k] = vec4<u32>(face, next, bitcast<u32>(lambda_exit));
    probe_out[2u * k + 1u] = vec4<u32>(bitcast<u32>(s_exit), 0u, 0u, 0u);
}
