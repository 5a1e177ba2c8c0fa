// Pass 1 of fragment PT (Marroquim et al. 2006, §3.2): one invocation per tet, the paper's
// first fragment shader done as a compute pass. Projects the four vertices, classifies the
// projection with four ternary sign tests into the 81-entry truth table, and writes the thick
// vertex, front/back scalars, thickness, fan and centroid depth. Mirrors
// `classify::classify_tet` (the CPU twin) operation by operation.

struct Params {
    view_proj: mat4x4<f32>,
    // xyz: eye; w: 1 for perspective, 0 for orthographic.
    eye: vec4<f32>,
    // xyz: unit view direction.
    forward: vec4<f32>,
    // x: scalar minimum, y: 1 / scalar range, z: 1 / length unit, w: zero-area tolerance.
    misc: vec4<f32>,
    // x: number of tets, y: first tet of this dispatch.
    counts: vec4<u32>,
}

struct TetOut {
    thick: vec4<f32>,
    s_front: f32,
    s_back: f32,
    thickness: f32,
    fan: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
// vertices_at, tets_at, records_set: declared by the Rust (render_core::ChunkedBuffer) at
// bindings 10.., each array split over as many storage bindings as the mesh needs.
@group(0) @binding(3) var<storage, read> truth_table: array<u32, 81>;
@group(0) @binding(5) var<storage, read_write> depths: array<f32>;
// The identity order (tet ids): the payload the GPU-resident sort permutes; the CPU orders
// overwrite it from the host.
@group(0) @binding(6) var<storage, read_write> order: array<u32>;

const FACES = array<vec3<u32>, 4>(vec3<u32>(1u, 2u, 3u), vec3<u32>(0u, 3u, 2u), vec3<u32>(0u, 1u, 3u), vec3<u32>(0u, 2u, 1u));

fn cross2(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

// Screen-space parameter along a projected segment -> parameter along the 3D segment.
fn perspective_t(t: f32, wa: f32, wb: f32) -> f32 {
    let a = (1.0 - t) / wa;
    let b = t / wb;
    if (a + b == 0.0) {
        return t;
    }
    return b / (a + b);
}

fn ring_of(cls: u32, p: vec4<u32>) -> array<u32, 5> {
    switch cls {
        case 1u: { return array<u32, 5>(p.y, p.z, p.w, p.y, 0u); }
        case 2u: { return array<u32, 5>(p.x, p.y, p.z, p.w, p.x); }
        case 3u: { return array<u32, 5>(p.y, p.z, p.w, 0u, 0u); }
        case 4u: { return array<u32, 5>(p.z, p.w, 0u, 0u, 0u); }
        default: { return array<u32, 5>(0u, 0u, 0u, 0u, 0u); }
    }
}

const TRIANGLES = array<u32, 5>(0u, 3u, 4u, 2u, 1u);

@compute @workgroup_size(64)
fn classify(@builtin(global_invocation_id) gid: vec3<u32>) {
    // 2D dispatch (more than 65535 workgroups of 64 on large meshes): counts.y threads a row.
    let t = gid.x + gid.y * params.counts.y;
    if (t >= params.counts.x) {
        return;
    }
    let tet = tets_at(t);
    var pos: array<vec3<f32>, 4>;
    var sc: array<f32, 4>;
    var clip: array<vec4<f32>, 4>;
    var q: array<vec2<f32>, 4>;
    var lo = vec2<f32>(3.0e38);
    var hi = vec2<f32>(-3.0e38);
    for (var i = 0u; i < 4u; i++) {
        let v = vertices_at(tet[i]);
        pos[i] = v.xyz;
        sc[i] = clamp((v.w - params.misc.x) * params.misc.y, 0.0, 1.0);
        clip[i] = params.view_proj * vec4<f32>(v.xyz, 1.0);
        q[i] = clip[i].xy / clip[i].w;
        lo = min(lo, q[i]);
        hi = max(hi, q[i]);
    }
    // Centroid sort key, as Camera::sort_distance (larger is farther).
    let centroid = 0.25 * (pos[0] + pos[1] + pos[2] + pos[3]);
    let d = centroid - params.eye.xyz;
    var key = dot(d, params.forward.xyz);
    if (params.eye.w > 0.5) {
        key = length(d);
    }
    depths[t] = key;
    order[t] = t;

    // The four sign tests (signed projected areas of the faces) -> ternary table index.
    let ext = max(hi.x - lo.x, hi.y - lo.y);
    let eps = params.misc.w * ext * ext;
    var idx = 0u;
    var pow3 = 1u;
    for (var i = 0u; i < 4u; i++) {
        let f = FACES[i];
        let area = cross2(q[f.y] - q[f.x], q[f.z] - q[f.x]);
        var digit = 1u;
        if (area > eps) {
            digit = 2u;
        } else if (area < -eps) {
            digit = 0u;
        }
        idx += digit * pow3;
        pow3 *= 3u;
    }
    let entry = truth_table[idx];
    let cls = entry & 7u;
    let perm = vec4<u32>((entry >> 8u) & 3u, (entry >> 10u) & 3u, (entry >> 12u) & 3u, (entry >> 14u) & 3u);
    let ring = ring_of(cls, perm);
    var fan = cls | (TRIANGLES[cls] << 4u);
    for (var i = 0u; i < 5u; i++) {
        fan |= ring[i] << (8u + 2u * i);
    }
    var out: TetOut;
    out.fan = fan;
    out.thick = vec4<f32>(0.0);
    out.s_front = 0.0;
    out.s_back = 0.0;
    out.thickness = 0.0;
    if (cls == 0u) {
        records_set(t, out);
        return;
    }
    let v0 = perm.x;
    let v1 = perm.y;
    let v2 = perm.z;
    let v3 = perm.w;
    var pa = pos[v0];
    var sa = sc[v0];
    var pb = pos[v1];
    var sb = sc[v1];
    if (cls == 1u) {
        let a = q[v1];
        let b = q[v2];
        let c = q[v3];
        let p = q[v0];
        let det = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        let l1 = ((p.x - a.x) * (c.y - a.y) - (p.y - a.y) * (c.x - a.x)) / det;
        let l2 = ((b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)) / det;
        let l0 = 1.0 - l1 - l2;
        var m0 = l0 / clip[v1].w;
        var m1 = l1 / clip[v2].w;
        var m2 = l2 / clip[v3].w;
        let sum = m0 + m1 + m2;
        m0 = m0 / sum;
        m1 = m1 / sum;
        m2 = m2 / sum;
        pb = m0 * pos[v1] + m1 * pos[v2] + m2 * pos[v3];
        sb = m0 * sc[v1] + m1 * sc[v2] + m2 * sc[v3];
    } else if (cls == 2u) {
        let a = q[v0];
        let b = q[v2];
        let c = q[v1];
        let dd = q[v3];
        let r = b - a;
        let u = dd - c;
        let den = r.x * u.y - r.y * u.x;
        let ac = c - a;
        let t2 = clamp((ac.x * u.y - ac.y * u.x) / den, 0.0, 1.0);
        let v = clamp((ac.x * r.y - ac.y * r.x) / den, 0.0, 1.0);
        let t3 = perspective_t(t2, clip[v0].w, clip[v2].w);
        let u3 = perspective_t(v, clip[v1].w, clip[v3].w);
        pa = pos[v0] + (pos[v2] - pos[v0]) * t3;
        sa = sc[v0] + (sc[v2] - sc[v0]) * t3;
        pb = pos[v1] + (pos[v3] - pos[v1]) * u3;
        sb = sc[v1] + (sc[v3] - sc[v1]) * u3;
    } else if (cls == 3u) {
        let a = q[v1];
        let dv = q[v3] - a;
        let ddv = dv.x * dv.x + dv.y * dv.y;
        var t2 = 0.0;
        if (ddv > 0.0) {
            t2 = clamp(((q[v0].x - a.x) * dv.x + (q[v0].y - a.y) * dv.y) / ddv, 0.0, 1.0);
        }
        let t3 = perspective_t(t2, clip[v1].w, clip[v3].w);
        pb = pos[v1] + (pos[v3] - pos[v1]) * t3;
        sb = sc[v1] + (sc[v3] - sc[v1]) * t3;
    }
    let ca = params.view_proj * vec4<f32>(pa, 1.0);
    let cb = params.view_proj * vec4<f32>(pb, 1.0);
    if (ca.z / ca.w <= cb.z / cb.w) {
        out.thick = ca;
        out.s_front = sa;
        out.s_back = sb;
    } else {
        out.thick = cb;
        out.s_front = sb;
        out.s_back = sa;
    }
    out.thickness = length(pa - pb) * params.misc.z;
    records_set(t, out);
}
