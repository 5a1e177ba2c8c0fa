// Shared by every raycast shader: the frame parameters, the mesh as a texture array (Table 1
// of the paper, 144 bytes per tet), the pixel ray, the ray–tet intersection
// of §2.2 (Eq. 1) and the scalar of Eq. 2. Concatenated in front of peel.wgsl and cast.wgsl.

const NONE: u32 = 0xffffffffu;
const BIG: f32 = 3.0e38;
const TEXELS: u32 = 9u;

const FLAG_ET: u32 = 1u;
const FLAG_TABLE3D: u32 = 2u;
const FLAG_COUNT_DROPPED: u32 = 4u;

struct Frame {
    // Pixel ray: origin = o0 + ndc.x·ox + ndc.y·oy, direction = normalize(d0 + ndc.x·dx + ndc.y·dy),
    // in object coordinates (mesh centred on its bounding box).
    o0: vec4<f32>,
    ox: vec4<f32>,
    oy: vec4<f32>,
    d0: vec4<f32>,
    dx: vec4<f32>,
    dy: vec4<f32>,
    view_proj: mat4x4<f32>,
    // width, height, tile width, tile height
    size: vec4<u32>,
    // tiles across, peel layers filled, step cap per ray, flags
    counts: vec4<u32>,
    // 1 / λ_far (depth of a peel fragment), peel bias on λ, opacity of early termination,
    // 1 / (table length: longest edge for 3D, fixed length for 2D)
    misc: vec4<f32>,
    // scalar entries, length entries, layer checked for dropped re-entries, unused
    table: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> frame: Frame;
// The mesh (layout.rs): layer `c` holds tets c·tets_per_layer.., nine texels each, in a
// render_core::texel_texture (`texel_at`, prepended by the Rust). A texel load is the paper's (t_u, t_v) texture fetch; a texture
// rather than a storage buffer, because a backend fetches a texel of every lane at once where
// a storage load may go lane by lane (the ray caster's frame halved on lavapipe).
@group(0) @binding(1) var mesh: texture_2d_array<u32>;

fn texel(c: u32, i: u32) -> vec4<u32> {
    return texel_at(mesh, c, i);
}

struct Ray {
    o: vec3<f32>,
    d: vec3<f32>,
}

// The frame's pixel-ray parameters ([`pixel_ray`]); an entry point whose rays start after
// divergent branches loads them first, where one load serves every invocation.
struct RayFrame {
    size: vec2<f32>,
    o0: vec3<f32>,
    ox: vec3<f32>,
    oy: vec3<f32>,
    d0: vec3<f32>,
    dx: vec3<f32>,
    dy: vec3<f32>,
}

fn ray_frame() -> RayFrame {
    return RayFrame(
        vec2<f32>(f32(frame.size.x), f32(frame.size.y)),
        frame.o0.xyz,
        frame.ox.xyz,
        frame.oy.xyz,
        frame.d0.xyz,
        frame.dx.xyz,
        frame.dy.xyz,
    );
}

// The ray through the pixel centre `px` (framebuffer coordinates, y down), as
// render_core::Camera::ray builds it.
fn ray_through(rf: RayFrame, px: vec2<f32>) -> Ray {
    let nx = px.x / rf.size.x * 2.0 - 1.0;
    let ny = 1.0 - px.y / rf.size.y * 2.0;
    var r: Ray;
    r.o = rf.o0 + nx * rf.ox + ny * rf.oy;
    r.d = normalize(rf.d0 + nx * rf.dx + ny * rf.dy);
    return r;
}

fn pixel_ray(px: vec2<f32>) -> Ray {
    return ray_through(ray_frame(), px);
}

// Eq. 1 for the four faces: numerators (v_{3−i} − e)·n_i and denominators r·n_i.
struct Planes {
    num: vec4<f32>,
    den: vec4<f32>,
}

fn planes(t: vec2<u32>, o: vec3<f32>, d: vec3<f32>) -> Planes {
    let b = t.y * TEXELS;
    let v0 = bitcast<vec4<f32>>(texel(t.x, b));
    let v1 = bitcast<vec4<f32>>(texel(t.x, b + 1u));
    let v2 = bitcast<vec4<f32>>(texel(t.x, b + 2u));
    let n0 = bitcast<vec4<f32>>(texel(t.x, b + 3u));
    let n1 = bitcast<vec4<f32>>(texel(t.x, b + 4u));
    let n2 = bitcast<vec4<f32>>(texel(t.x, b + 5u));
    let v3 = vec3<f32>(v0.w, v1.w, v2.w);
    let n3 = vec3<f32>(n0.w, n1.w, n2.w);
    var p: Planes;
    p.num = vec4<f32>(
        dot(v3 - o, n0.xyz),
        dot(v2.xyz - o, n1.xyz),
        dot(v1.xyz - o, n2.xyz),
        dot(v0.xyz - o, n3),
    );
    p.den = vec4<f32>(dot(d, n0.xyz), dot(d, n1.xyz), dot(d, n2.xyz), dot(d, n3));
    return p;
}

// s(x) = g·x + c (Eq. 2), normalised to the transfer function's [0, 1].
fn scalar_at(t: vec2<u32>, x: vec3<f32>) -> f32 {
    let g = bitcast<vec4<f32>>(texel(t.x, t.y * TEXELS + 8u));
    return dot(g.xyz, x) + g.w;
}

// Entry parameter of the ray into tet `t`: the largest λ among faces with a negative
// denominator (§2.2), as the first-hit and peeling shaders compute it.
fn entry_lambda(t: vec2<u32>, o: vec3<f32>, d: vec3<f32>) -> f32 {
    let p = planes(t, o, d);
    var best = -BIG;
    for (var i = 0u; i < 4u; i++) {
        if p.den[i] < 0.0 {
            best = max(best, p.num[i] / p.den[i]);
        }
    }
    if best == -BIG {
        best = 0.0;
    }
    return best;
}

// One step's geometry (phase 3a): the exit face is the smallest λ among faces with a positive
// denominator (§2.2; the entry face needs no stored index), never behind the current λ; the
// next tet is the neighbour across it (NONE: the ray leaves the mesh).
struct Exit {
    face: u32,
    next: vec2<u32>,
    lambda: f32,
    s: f32,
}

fn exit_of(t: vec2<u32>, o: vec3<f32>, d: vec3<f32>, lambda: f32) -> Exit {
    let pl = planes(t, o, d);
    var best = BIG;
    var out: Exit;
    out.face = 4u;
    for (var f = 0u; f < 4u; f++) {
        if pl.den[f] > 0.0 {
            let l = pl.num[f] / pl.den[f];
            if l < best {
                best = l;
                out.face = f;
            }
        }
    }
    out.lambda = lambda;
    out.next = vec2<u32>(NONE, NONE);
    if out.face < 4u {
        out.lambda = max(best, lambda);
        let nb = texel(t.x, t.y * TEXELS + 6u + out.face / 2u);
        if (out.face & 1u) == 0u {
            out.next = nb.xy;
        } else {
            out.next = nb.zw;
        }
    }
    out.s = scalar_at(t, o + out.lambda * d);
    return out;
}
