// Splatting one slab (Grau & Tost §3.6): one quad per voxel of buckets i - r ... i + r (the
// paper draws point sprites), its footprint slice looked up in the table of all slices and
// added to the sheet: rg = (sum of value * footprint, sum of footprint).

struct Slab {
    index: u32,
}

@group(0) @binding(0) var<uniform> fr: Frame;
@group(0) @binding(1) var<storage, read> sorted_in: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> table: array<f32>;
@group(0) @binding(3) var image_tex: texture_2d<f32>;
// Splat fragments early splat elimination dropped (the row's `ese_dropped_fragments`).
@group(0) @binding(4) var<storage, read_write> ese_dropped: atomic<u32>;
@group(1) @binding(0) var<uniform> slab: Slab;

struct SplatOut {
    @builtin(position) pos: vec4<f32>,
    // Offset from the voxel centre in kernel units.
    @location(0) kxy: vec2<f32>,
    // Voxel centre behind the slab's front plane, in slabs.
    @location(1) @interpolate(flat) delta: f32,
    @location(2) @interpolate(flat) value: f32,
}

@vertex
fn splat_vs(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> SplatOut {
    var out: SplatOut;
    let v = sorted_in[ii];
    let d = view_depth(fr, v.xyz);
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(-1.0, 1.0),
        vec2<f32>(-1.0, 1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0));
    let c = corners[vi];
    let clip = fr.view_proj * vec4<f32>(v.xyz, 1.0);
    if (clip.w <= 0.0 || d <= 0.0) {
        out.pos = vec4<f32>(2.0, 2.0, 2.0, 1.0);
        return out;
    }
    let ndc = clip.xy / clip.w;
    var ppw = fr.focal_px;
    if (fr.perspective != 0u) {
        ppw = fr.focal_px / d;
    }
    let half_px = fr.kernel_radius_world * ppw;
    let centre = vec2<f32>((ndc.x + 1.0) * 0.5 * fr.viewport.x, (1.0 - ndc.y) * 0.5 * fr.viewport.y);
    let corner = centre + c * half_px;
    out.pos = vec4<f32>(corner.x / fr.viewport.x * 2.0 - 1.0, 1.0 - corner.y / fr.viewport.y * 2.0, 0.5, 1.0);
    out.kxy = c * fr.kernel_radius;
    out.delta = (d - fr.d0) * fr.inv_delta - f32(slab.index);
    out.value = v.w;
    return out;
}

fn texel(q: u32, tx: i32, ty: i32) -> f32 {
    let n = i32(fr.footprint);
    if (tx < 0 || ty < 0 || tx >= n || ty >= n) {
        return 0.0;
    }
    return table[q * fr.footprint * fr.footprint + u32(ty) * fr.footprint + u32(tx)];
}

fn tile(q: u32, u: f32, v: f32) -> f32 {
    let x0 = floor(u);
    let y0 = floor(v);
    let fx = u - x0;
    let fy = v - y0;
    let ix = i32(x0);
    let iy = i32(y0);
    return mix(mix(texel(q, ix, iy), texel(q, ix + 1, iy), fx),
               mix(texel(q, ix, iy + 1), texel(q, ix + 1, iy + 1), fx), fy);
}

// Twin of FootprintTable::sample (kernel.rs): linear between slice rows, bilinear in a slice.
fn footprint(delta: f32, kxy: vec2<f32>) -> f32 {
    let rows = (2u * fr.radius_slabs + 1u) * fr.subslices + 1u;
    let qf = clamp((delta + f32(fr.radius_slabs)) * f32(fr.subslices), 0.0, f32(rows - 1u));
    let q0 = min(u32(floor(qf)), rows - 2u);
    let fq = qf - f32(q0);
    let f = f32(fr.footprint);
    let u = (kxy.x + fr.kernel_radius) / (2.0 * fr.kernel_radius) * f - 0.5;
    let v = (kxy.y + fr.kernel_radius) / (2.0 * fr.kernel_radius) * f - 0.5;
    return mix(tile(q0, u, v), tile(q0 + 1u, u, v), fq);
}

@fragment
fn splat_fs(in: SplatOut) -> @location(0) vec4<f32> {
    // Early splat elimination: nothing behind an opaque pixel can show.
    if (fr.ese_alpha <= 1.0) {
        let a = textureLoad(image_tex, vec2<i32>(in.pos.xy), 0).a;
        if (a >= fr.ese_alpha) {
            atomicAdd(&ese_dropped, 1u);
            discard;
        }
    }
    let w = footprint(in.delta, in.kxy) * fr.density_scale;
    return vec4<f32>(w * in.value, w, 0.0, 0.0);
}
