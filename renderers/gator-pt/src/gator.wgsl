// GATOR-style projected tetrahedra (Wylie, Moreland, Fisk, Crossno 2002, "Tetrahedral
// projection using vertex shaders").
//
// Every vertex-shader invocation reads its tet's four vertices from storage, projects them,
// runs the paper's four tests (Fig. 5), picks the basis-graph mapping of Table 1 and emits one
// node of the basis graph (5 per tet). wgpu has no triangle fans, so an index buffer draws each
// tet's fan as 4 triangles = 12 indices over its 5 nodes (the fourth triangle degenerates for
// class 1). `project_and_classify` is the single copy
// of the classification: the vertex shader and the debug compute entry point both call it,
// and classify.rs is its f64 twin (keep the two in step).

struct Params {
    view_proj: mat4x4<f32>,
    // Elements per storage binding of the tet and point arrays (meshes larger than one
    // binding are split across tets0..3 / points0..2).
    tets_per_chunk: u32,
    points_per_chunk: u32,
    num_tets: u32,
    // 0: constant cells (the tet's mean scalar), 1: linear cells (s_front, s_back).
    cells: u32,
    inv_length_unit: f32,
    tau_max: f32,
    tf_size: u32,
    exp_size: u32,
};

struct ChunkParams {
    // Sorted position of this chunk's first entry in `order` (in the debug pass: the first
    // tet of the chunk it classifies).
    base: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
};

// What the debug entry point records per tet (80 bytes; mirrored by `GpuClassification`).
struct DebugRecord {
    // Screen x and y (NDC) of the four input vertices as this shader projected them.
    screen_x: vec4<f32>,
    screen_y: vec4<f32>,
    case_id: u32,
    class_id: u32,
    // Bit i set: test t(i+1) held (t1..t3 the orientation tests, t4 the class-2 test).
    tests: u32,
    pad0: u32,
    thick: vec2<f32>,
    ndc_thickness: f32,
    length: f32,
    s_front: f32,
    s_back: f32,
    pad1: vec2<u32>,
};

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> tets0: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> tets1: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> tets2: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> tets3: array<vec4<u32>>;
// xyz and the normalised scalar.
@group(0) @binding(5) var<storage, read> points0: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> points1: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> points2: array<vec4<f32>>;
// Lookup tables (the paper shades through tables): chromaticity rgb + extinction κ over the
// normalised scalar, and α(τ) = 1 − exp(−τ) over τ ∈ [0, tau_max].
@group(0) @binding(8) var tf_lut: texture_1d<f32>;
@group(0) @binding(9) var exp_lut: texture_1d<f32>;

// Back-to-front order of tet ids for this chunk of the draw.
@group(1) @binding(0) var<storage, read> order: array<u32>;
@group(1) @binding(1) var<uniform> C: ChunkParams;
// Debug path only.
@group(1) @binding(2) var<storage, read_write> debug_out: array<DebugRecord>;

fn tet_at(id: u32) -> vec4<u32> {
    let c = id / P.tets_per_chunk;
    let i = id - c * P.tets_per_chunk;
    switch c {
        case 0u: { return tets0[i]; }
        case 1u: { return tets1[i]; }
        case 2u: { return tets2[i]; }
        default: { return tets3[i]; }
    }
}

fn point_at(id: u32) -> vec4<f32> {
    let c = id / P.points_per_chunk;
    let i = id - c * P.points_per_chunk;
    switch c {
        case 0u: { return points0[i]; }
        case 1u: { return points1[i]; }
        default: { return points2[i]; }
    }
}

// The authors' MappingTable (gator.cg): input vertex in slots v0', v1', v2', v3' for
// idx = 4·t1 + 2·t2 + t3. The hull is then v0', v3', v1', v2' (or v0', v3', v2' with v1'
// inside).
const MAPPING = array<vec4<u32>, 8>(
    vec4<u32>(0u, 3u, 1u, 2u),
    vec4<u32>(0u, 3u, 2u, 1u),
    vec4<u32>(0u, 2u, 1u, 3u),
    vec4<u32>(0u, 2u, 3u, 1u),
    vec4<u32>(0u, 1u, 3u, 2u),
    vec4<u32>(0u, 1u, 2u, 3u),
    vec4<u32>(2u, 0u, 3u, 1u),
    vec4<u32>(3u, 0u, 2u, 1u),
);

struct TetProjection {
    // Per input vertex (lanes x, y, z, w = vertices 0..3): screen x, y (NDC) and scalar.
    x: vec4<f32>,
    y: vec4<f32>,
    s: vec4<f32>,
    perm: vec4<u32>,
    thick: vec2<f32>,
    // World length of the eye-ray segment through the thick vertex (§3.5).
    length: f32,
    s_front: f32,
    s_back: f32,
    s_mean: f32,
    ndc_thickness: f32,
    case_id: u32,
    class2: bool,
    // Bit i: test t(i+1) held (the debug record's `tests`).
    tests: u32,
    // false when a vertex is behind the eye (w <= 0): the tet is not drawn.
    valid: bool,
};

fn cross2(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

// 1 in the lane of vertex `i`, 0 elsewhere: selecting vertex i is a dot product with this
// mask, as gator.cg's `multiplex` does (no dynamic indexing, which vertex pipelines handle
// badly).
fn lane(i: u32) -> vec4<f32> {
    return select(vec4<f32>(0.0), vec4<f32>(1.0), vec4<u32>(0u, 1u, 2u, 3u) == vec4<u32>(i));
}

fn project_and_classify(tet_id: u32) -> TetProjection {
    var r: TetProjection;
    let t = tet_at(tet_id);
    let p0 = point_at(t.x);
    let p1 = point_at(t.y);
    let p2 = point_at(t.z);
    let p3 = point_at(t.w);
    let c0 = P.view_proj * vec4<f32>(p0.xyz, 1.0);
    let c1 = P.view_proj * vec4<f32>(p1.xyz, 1.0);
    let c2 = P.view_proj * vec4<f32>(p2.xyz, 1.0);
    let c3 = P.view_proj * vec4<f32>(p3.xyz, 1.0);
    let w_raw = vec4<f32>(c0.w, c1.w, c2.w, c3.w);
    r.valid = all(w_raw > vec4<f32>(0.0));
    let w = max(w_raw, vec4<f32>(1e-30));
    let inv_w = 1.0 / w;
    let x = vec4<f32>(c0.x, c1.x, c2.x, c3.x) * inv_w;
    let y = vec4<f32>(c0.y, c1.y, c2.y, c3.y) * inv_w;
    let z = vec4<f32>(c0.z, c1.z, c2.z, c3.z) * inv_w;
    let s = vec4<f32>(p0.w, p1.w, p2.w, p3.w);
    r.x = x;
    r.y = y;
    r.s = s;
    r.s_mean = 0.25 * (s.x + s.y + s.z + s.w);

    // Tests 1-3 (Fig. 5; gator.cg tests123). A zero cross product counts as positive so ties
    // (coincident or collinear points) still put a proper vertex into slot v1'.
    let e1 = vec2<f32>(x.y - x.x, y.y - y.x);
    let e2 = vec2<f32>(x.z - x.x, y.z - y.x);
    let e3 = vec2<f32>(x.w - x.x, y.w - y.x);
    let a = cross2(e1, e2);
    let b = cross2(e1, e3);
    let c = cross2(e3, e2);
    let t1 = (a >= 0.0) != (b >= 0.0);
    let t2 = (a >= 0.0) != (c >= 0.0);
    let t3 = a >= 0.0;
    let idx = 4u * u32(t1) + 2u * u32(t2) + u32(t3);
    var mapping = MAPPING;
    let perm = mapping[idx];
    r.perm = perm;
    let m0 = lane(perm.x);
    let m1 = lane(perm.y);
    let m2 = lane(perm.z);
    let m3 = lane(perm.w);
    let q0 = vec2<f32>(dot(m0, x), dot(m0, y));
    let q1 = vec2<f32>(dot(m1, x), dot(m1, y));
    let q2 = vec2<f32>(dot(m2, x), dot(m2, y));
    let q3 = vec2<f32>(dot(m3, x), dot(m3, y));

    // Intersection of v0'v1' with v2'v3': 0 = C + α A − β B (gator.cg compute_intersection).
    let av = q1 - q0;
    let bv = q3 - q2;
    let cv = q0 - q2;
    let den = cross2(av, bv);
    let alpha_num = cross2(bv, cv);
    let beta_num = cross2(av, cv);

    // Test 4: α < 1 → all four on the hull (class 2); never for idx 6, 7 (the two impossible
    // rows: v0 strictly inside the other three).
    var t4 = false;
    if idx < 6u && den != 0.0 {
        t4 = alpha_num / den < 1.0;
    }
    var beta = 0.0;
    if den != 0.0 {
        beta = clamp(beta_num / den, 0.0, 1.0);
    }
    // Projected-space weights (over input vertices) of the two ends of the thick segment.
    var wa: vec4<f32>;
    var wb: vec4<f32>;
    if t4 {
        let alpha = clamp(alpha_num / den, 0.0, 1.0);
        wa = m0 * (1.0 - alpha) + m1 * alpha;
        wb = m2 * (1.0 - beta) + m3 * beta;
    } else {
        // Class 1: thick vertex v1'; far end on face v0'v2'v3' at r = 1/α along v0' → I.
        var rr = 0.0;
        if alpha_num != 0.0 {
            rr = clamp(den / alpha_num, 0.0, 1.0);
        }
        wa = m1;
        wb = m0 * (1.0 - rr) + m2 * (rr * (1.0 - beta)) + m3 * (rr * beta);
    }
    r.thick = vec2<f32>(dot(wa, x), dot(wa, y));
    let za = dot(wa, z);
    let zb = dot(wb, z);
    // World points: projected weights λ become world weights λᵢ/wᵢ, normalised
    // (perspective-correct; exact because a projective map keeps lines straight).
    let ga = wa * inv_w;
    let gb = wb * inv_w;
    let world = mat4x3<f32>(p0.xyz, p1.xyz, p2.xyz, p3.xyz);
    let sum_a = dot(ga, vec4<f32>(1.0));
    let sum_b = dot(gb, vec4<f32>(1.0));
    let pa = (world * ga) / sum_a;
    let pb = (world * gb) / sum_b;
    let sa = dot(ga, s) / sum_a;
    let sb = dot(gb, s) / sum_b;
    r.length = length(pa - pb);
    r.ndc_thickness = abs(za - zb);
    if za <= zb {
        r.s_front = sa;
        r.s_back = sb;
    } else {
        r.s_front = sb;
        r.s_back = sa;
    }
    r.class2 = t4;
    r.tests = u32(t1) | (u32(t2) << 1u) | (u32(t3) << 2u) | (u32(t4) << 3u);
    if idx < 6u {
        r.case_id = 2u * idx + 1u + u32(t4);
    } else {
        r.case_id = 13u + idx - 6u;
    }
    return r;
}

struct VsOut {
    @builtin(position) pos: vec4<f32>,
    // World thickness (0 on the silhouette), s_front, s_back: interpolated linearly on screen
    // as in Shirley–Tuchman / GATOR (exact for orthographic views).
    @location(0) @interpolate(linear) seg: vec3<f32>,
};

// One invocation per basis-graph node: vertex 5k + j is node j of the k-th tet in the sorted
// order. The index buffer lists each tet's fan as 4 triangles of these 5 nodes,
// (0,1,2) (0,2,3) (0,3,4) (0,4,1); node 0 is the thick vertex, nodes 1..4 the rim
// v2', v0', v3', then v1' (class 2) or v2' again (class 1: the fourth triangle degenerates).
@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VsOut {
    let k = vi / 5u;
    let node = vi - 5u * k;
    let tet_id = order[k - C.base];
    let tp = project_and_classify(tet_id);
    var out: VsOut;
    if !tp.valid {
        out.pos = vec4<f32>(0.0, 0.0, 0.5, 1.0);
        out.seg = vec3<f32>(0.0);
        return out;
    }
    var xy: vec2<f32>;
    var seg: vec3<f32>;
    if node == 0u {
        xy = tp.thick;
        seg = vec3<f32>(tp.length, tp.s_front, tp.s_back);
    } else {
        var v = tp.perm.z;
        if node == 2u {
            v = tp.perm.x;
        } else if node == 3u {
            v = tp.perm.w;
        } else if node == 4u && tp.class2 {
            v = tp.perm.y;
        }
        let m = lane(v);
        xy = vec2<f32>(dot(m, tp.x), dot(m, tp.y));
        let sv = dot(m, tp.s);
        seg = vec3<f32>(0.0, sv, sv);
    }
    if P.cells == 0u {
        seg.y = tp.s_mean;
        seg.z = tp.s_mean;
    }
    // w = 1: no perspective division of the attributes, no depth clipping (no depth test).
    out.pos = vec4<f32>(xy, 0.5, 1.0);
    out.seg = seg;
    return out;
}

fn lut_tf(s: f32) -> vec4<f32> {
    let x = clamp(s, 0.0, 1.0) * f32(P.tf_size - 1u);
    let i0 = min(u32(floor(x)), P.tf_size - 1u);
    let i1 = min(i0 + 1u, P.tf_size - 1u);
    return mix(textureLoad(tf_lut, i0, 0), textureLoad(tf_lut, i1, 0), x - f32(i0));
}

fn lut_opacity(tau: f32) -> f32 {
    let x = clamp(tau / P.tau_max, 0.0, 1.0) * f32(P.exp_size - 1u);
    let i0 = min(u32(floor(x)), P.exp_size - 1u);
    let i1 = min(i0 + 1u, P.exp_size - 1u);
    return mix(textureLoad(exp_lut, i0, 0).x, textureLoad(exp_lut, i1, 0).x, x - f32(i0));
}

// Emission–absorption with the average scalar of the segment (the paper's shading):
// colour c(s̄), opacity α = 1 − exp(−κ(s̄)·l / length_unit), premultiplied for "over".
@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let s = 0.5 * (in.seg.y + in.seg.z);
    let tf = lut_tf(s);
    let tau = max(tf.w, 0.0) * max(in.seg.x, 0.0) * P.inv_length_unit;
    let alpha = lut_opacity(tau);
    return vec4<f32>(tf.rgb * alpha, alpha);
}

// Debug: the classification of tets C.base, C.base + 1, …, written to a buffer from its
// start (debug.rs reads it back chunk by chunk; the tests and the claims compare it with
// classify.rs and with the projected hull).
@compute @workgroup_size(64)
fn classify_debug(@builtin(global_invocation_id) gid: vec3<u32>) {
    let id = C.base + gid.x;
    if id >= P.num_tets || gid.x >= arrayLength(&debug_out) {
        return;
    }
    let tp = project_and_classify(id);
    var rec: DebugRecord;
    rec.screen_x = tp.x;
    rec.screen_y = tp.y;
    rec.tests = tp.tests;
    rec.case_id = tp.case_id;
    rec.class_id = select(1u, 2u, tp.class2);
    if !tp.valid {
        rec.class_id = 0u;
    }
    rec.thick = tp.thick;
    rec.ndc_thickness = tp.ndc_thickness;
    rec.length = tp.length;
    rec.s_front = tp.s_front;
    rec.s_back = tp.s_back;
    debug_out[gid.x] = rec;
}
