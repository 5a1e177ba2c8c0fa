// The bitonic sort of (key, value) pairs over a power-of-two length (at least 4), ascending by
// (key, value) so that the order equals a stable sort of the keys (values are the original
// indices). Grau & Tost §3.4 sort with Govindaraju et al.'s GPU bitonic network; this is the
// same network, every compare-exchange (k, j) in the same order, four per invocation:
//
// * `bitonic_double`: two stages (k, j) and (k, j / 2) with j >= 8 over four aligned vec4s
//   (i, i + j/2, i + j, i + 3j/2): every element is read and written once for two stages;
// * `bitonic_wide`: one stage (k, j) with j >= 4: the four pairs (i + c, i + c + j), c < 4,
//   are two aligned vec4s;
// * `bitonic_narrow`: the stages (k, 2) and (k, 1), or (2, 1) alone, inside one aligned vec4.
//
// On lavapipe each invocation's loads are gathers lane by lane: four pairs per invocation and
// vec4 loads cut them fourfold against one scalar pair per invocation, and a stage over 16 M
// keys streams 128 MB, so two stages a pass halve the traffic.

struct Stage {
    k: u32,
    j: u32,
    n: u32,
    pad: u32,
}

@group(0) @binding(0) var<storage, read> st: Stage;
@group(0) @binding(1) var<storage, read_write> keys: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> vals: array<vec4<u32>>;

fn flat_id(g: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return g.x + g.y * nwg.x * 256u;
}

@compute @workgroup_size(256)
fn bitonic_wide(@builtin(global_invocation_id) g: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    // Invocation t takes pairs 4t ... 4t + 3; pair p's first element keeps p's bits below j
    // and moves the rest up one place.
    let p = 4u * flat_id(g, nwg);
    if (p >= st.n / 2u) {
        return;
    }
    let i = ((p & ~(st.j - 1u)) << 1u) | (p & (st.j - 1u));
    let a = i / 4u;
    let b = (i + st.j) / 4u;
    let ka = keys[a];
    let kb = keys[b];
    let va = vals[a];
    let vb = vals[b];
    // k >= 2j >= 8: one direction for all four.
    let ascending = (i & st.k) == 0u;
    let greater = (ka > kb) | ((ka == kb) & (va > vb));
    let swap = greater == vec4<bool>(ascending);
    if (any(swap)) {
        keys[a] = select(ka, kb, swap);
        keys[b] = select(kb, ka, swap);
        vals[a] = select(va, vb, swap);
        vals[b] = select(vb, va, swap);
    }
}

// Compare-exchange of four pairs (a[c], b[c]) in one direction.
fn exchange4(ka: ptr<function, vec4<f32>>, kb: ptr<function, vec4<f32>>, va: ptr<function, vec4<u32>>, vb: ptr<function, vec4<u32>>, ascending: bool) {
    let greater = (*ka > *kb) | ((*ka == *kb) & (*va > *vb));
    let swap = greater == vec4<bool>(ascending);
    let k0 = *ka;
    let v0 = *va;
    *ka = select(*ka, *kb, swap);
    *kb = select(*kb, k0, swap);
    *va = select(*va, *vb, swap);
    *vb = select(*vb, v0, swap);
}

@compute @workgroup_size(256)
fn bitonic_double(@builtin(global_invocation_id) g: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    // Invocation t takes elements e = 4t ... 4t + 3 of the n / 4 group starts; a start keeps
    // e's bits below h = j / 2 and moves the rest up past bits h and j (both clear).
    let e = 4u * flat_id(g, nwg);
    if (e >= st.n / 4u) {
        return;
    }
    let h = st.j / 2u;
    let i = ((e & ~(h - 1u)) << 2u) | (e & (h - 1u));
    let a = i / 4u;
    let b = (i + h) / 4u;
    let c = (i + st.j) / 4u;
    let d = (i + st.j + h) / 4u;
    var ka = keys[a];
    var kb = keys[b];
    var kc = keys[c];
    var kd = keys[d];
    var va = vals[a];
    var vb = vals[b];
    var vc = vals[c];
    var vd = vals[d];
    // k >= 2j: one direction for all sixteen elements, in both stages.
    let ascending = (i & st.k) == 0u;
    // Stage (k, j): i with i + j, i + h with i + h + j.
    exchange4(&ka, &kc, &va, &vc, ascending);
    exchange4(&kb, &kd, &vb, &vd, ascending);
    // Stage (k, h): i with i + h, i + j with i + j + h.
    exchange4(&ka, &kb, &va, &vb, ascending);
    exchange4(&kc, &kd, &vc, &vd, ascending);
    keys[a] = ka;
    keys[b] = kb;
    keys[c] = kc;
    keys[d] = kd;
    vals[a] = va;
    vals[b] = vb;
    vals[c] = vc;
    vals[d] = vd;
}

// Compare-exchange of components x < y of (k4, v4) in the direction `ascending`.
fn exchange(k4: ptr<function, vec4<f32>>, v4: ptr<function, vec4<u32>>, x: u32, y: u32, ascending: bool) {
    let kx = (*k4)[x];
    let ky = (*k4)[y];
    let vx = (*v4)[x];
    let vy = (*v4)[y];
    let greater = kx > ky || (kx == ky && vx > vy);
    if (greater == ascending) {
        (*k4)[x] = ky;
        (*k4)[y] = kx;
        (*v4)[x] = vy;
        (*v4)[y] = vx;
    }
}

@compute @workgroup_size(256)
fn bitonic_narrow(@builtin(global_invocation_id) g: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let t = flat_id(g, nwg);
    if (t >= st.n / 4u) {
        return;
    }
    let i = 4u * t;
    var k4 = keys[t];
    var v4 = vals[t];
    if (st.k >= 4u) {
        // Stage (k, 2): one direction for the vec4.
        let ascending = (i & st.k) == 0u;
        exchange(&k4, &v4, 0u, 2u, ascending);
        exchange(&k4, &v4, 1u, 3u, ascending);
    }
    // Stage (k, 1): the second pair's direction differs from the first's only when k = 2.
    exchange(&k4, &v4, 0u, 1u, (i & st.k) == 0u);
    exchange(&k4, &v4, 2u, 3u, ((i + 2u) & st.k) == 0u);
    keys[t] = k4;
    vals[t] = v4;
}
