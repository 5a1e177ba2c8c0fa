// Pass 2 of fragment PT (Marroquim et al. 2006, §3.3–3.4): draws each tet's fan as 4 triangles
// (12 vertices; triangles past the fan's count are degenerate, wgpu has no fans), back to front
// in the order given by `order`. Silhouette vertices carry thickness 0 and s_f = s_b = their
// scalar; the thick vertex carries pass 1's s_f, s_b and l; the rasterizer interpolates them.
//
// Shading (fragment stage):
//  * `fs_average`: the average scalar (s_f + s_b) / 2 through the transfer function and
//    α = 1 − e^(−κ l) read from a 1D exponential table (Shirley & Tuchman 1990);
//  * `fs_psi`: partial pre-integration (Moreland & Angel 2004, the paper's §3.4) with the ψ
//    table, colours and extinctions looked up at s_f and s_b.
// Output is premultiplied; blending is `src + (1 − src.a)·dst` (back to front).

struct Params {
    view_proj: mat4x4<f32>,
    // x: scalar minimum, y: 1 / scalar range, z: max optical depth of the exp table,
    // w: unused.
    misc: vec4<f32>,
    // x: transfer-function entries, y: exp-table entries, z: ψ-table side.
    sizes: vec4<u32>,
}

struct TetOut {
    thick: vec4<f32>,
    s_front: f32,
    s_back: f32,
    thickness: f32,
    fan: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
// vertices_at, tets_at, records_at: declared by the Rust (render_core::ChunkedBuffer) at
// bindings 10.., split over as many storage bindings as the mesh needs.
@group(0) @binding(4) var<storage, read> order: array<u32>;
// The tables are textures read with textureLoad and interpolated here: a CPU backend gathers a
// texel fetch across lanes, where it loads storage with per-fragment addresses lane by lane
// (render_core::bind::lookup_texture).
// Transfer function sampled at n points: rgb chromaticity, a = κ per length unit.
@group(0) @binding(5) var tf: texture_1d<f32>;
// e^(−x) for x in [0, misc.z], n points (Shirley–Tuchman's exponential table).
@group(0) @binding(6) var exp_table: texture_1d<f32>;
// ψ(γ_f, γ_b), side n, γ_b as the row (see render_core::preintegration).
@group(0) @binding(7) var psi_table: texture_2d<f32>;

struct VsOut {
    @builtin(position) pos: vec4<f32>,
    // x: s_front, y: s_back, z: thickness (length units).
    @location(0) @interpolate(linear) attrs: vec3<f32>,
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VsOut {
    let slot = vi / 12u;
    let corner = vi % 12u;
    let tri = corner / 3u;
    let k = corner % 3u;
    let t = order[slot];
    let rec = records_at(t);
    var out: VsOut;
    let ntri = (rec.fan >> 4u) & 7u;
    if (tri >= ntri) {
        // Unused triangle of the fan: all three corners at one point, nothing rasterised.
        out.pos = vec4<f32>(0.0, 0.0, 0.5, 1.0);
        out.attrs = vec3<f32>(0.0);
        return out;
    }
    if (k == 0u) {
        out.pos = rec.thick;
        out.attrs = vec3<f32>(rec.s_front, rec.s_back, rec.thickness);
        return out;
    }
    let ri = tri + k - 1u;
    let local = (rec.fan >> (8u + 2u * ri)) & 3u;
    let v = vertices_at(tets_at(t)[local]);
    let s = clamp((v.w - params.misc.x) * params.misc.y, 0.0, 1.0);
    out.pos = params.view_proj * vec4<f32>(v.xyz, 1.0);
    out.attrs = vec3<f32>(s, s, 0.0);
    return out;
}

// Linear interpolation in the transfer-function table (entry i ↔ s = i / (n − 1)).
fn tf_at(s: f32) -> vec4<f32> {
    let n = params.sizes.x;
    let x = clamp(s, 0.0, 1.0) * f32(n - 1u);
    let i = min(u32(floor(x)), n - 2u);
    let f = x - f32(i);
    return mix(textureLoad(tf, i, 0), textureLoad(tf, i + 1u, 0), f);
}

// e^(−x) from the exponential table, linear interpolation; 0 beyond its range.
fn exp_neg(x: f32) -> f32 {
    let n = params.sizes.y;
    let u = max(x, 0.0) / params.misc.z * f32(n - 1u);
    if (u >= f32(n - 1u)) {
        return 0.0;
    }
    let i = u32(floor(u));
    let f = u - f32(i);
    return mix(textureLoad(exp_table, i, 0).x, textureLoad(exp_table, i + 1u, 0).x, f);
}

fn psi_at_texel(i: u32, j: u32) -> f32 {
    return textureLoad(psi_table, vec2<u32>(i, j), 0).x;
}

// Bilinear ψ lookup (entry i ↔ γ = i / (n − 1)).
fn psi_at(gf: f32, gb: f32) -> f32 {
    let n = params.sizes.z;
    let x = clamp(gf, 0.0, 1.0) * f32(n - 1u);
    let y = clamp(gb, 0.0, 1.0) * f32(n - 1u);
    let i = min(u32(floor(x)), n - 2u);
    let j = min(u32(floor(y)), n - 2u);
    let fx = x - f32(i);
    let fy = y - f32(j);
    let a = mix(psi_at_texel(i, j), psi_at_texel(i + 1u, j), fx);
    let b = mix(psi_at_texel(i, j + 1u), psi_at_texel(i + 1u, j + 1u), fx);
    return mix(a, b, fy);
}

@fragment
fn fs_average(in: VsOut) -> @location(0) vec4<f32> {
    let s = 0.5 * (in.attrs.x + in.attrs.y);
    let c = tf_at(s);
    let alpha = 1.0 - exp_neg(c.a * max(in.attrs.z, 0.0));
    return vec4<f32>(c.rgb * alpha, alpha);
}

@fragment
fn fs_psi(in: VsOut) -> @location(0) vec4<f32> {
    let l = max(in.attrs.z, 0.0);
    let cf = tf_at(in.attrs.x);
    let cb = tf_at(in.attrs.y);
    let tau_f = cf.a * l;
    let tau_b = cb.a * l;
    let zeta = exp_neg(0.5 * (tau_f + tau_b));
    let psi = psi_at(tau_f / (tau_f + 1.0), tau_b / (tau_b + 1.0));
    let rgb = cb.rgb * (psi - zeta) + cf.rgb * (1.0 - psi);
    return vec4<f32>(rgb, 1.0 - zeta);
}
