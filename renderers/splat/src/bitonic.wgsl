// The bitonic sort of (key, value) pairs over a power-of-two length (at least 4), ascending by
// (key, value) so that the order equals a stable sort of the keys (values are the original
// indices). Grau & Tost §3.4 sort with Govindaraju et al.'s GPU bitonic network; this is the
// same network, every compare-exchange (k, j) in the same order, four per invocation:
//
// * `bitonic_wide`: one stage (k, j) with j >= 4: the four pairs (i + c, i + c + j), c < 4,
//   are two aligned vec4s;
// * `bitonic_narrow`: the stages (k, 2) and (k, 1), or (2, 1) alone, inside one aligned vec4.
//
// On lavapipe each invocation's loads are gathers lane by lane: four pairs per invocation and
// vec4 loads cut them fourfold against one scalar pair per invocation.

struct Stage {
    k: u32,
    j: u32,
    n: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> st: Stage;
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
