// Classifies and composites one slab's sheet (post-classification): ring slot `slab.slot`
// holds the slab's fixed-point sums (value * w, w) (splat.wgsl), so its mean value is
// sum v*w / sum w and its coverage sum w; the transfer function is applied to the mean, the
// extinction weighted by the coverage (so the data set's boundary keeps its mass), over the
// ray's length through the slab; front-to-back "under" blending into the image. The pixel's
// sums are zeroed as they are read: the slot is empty, without a clear pass, for the slab
// 2r + 1 further on.

// 1 / SHEET_ONE (splat.wgsl).
const SHEET_UNIT: f32 = 1.0 / 16777216.0;

@group(0) @binding(0) var<storage, read> fr: Frame;
@group(0) @binding(1) var<storage, read_write> sheet: array<u32>;
@group(0) @binding(2) var<storage, read> tf: array<vec4<f32>>;
@group(1) @binding(0) var<storage, read> slab: Slab;

// The vertex stage is render_core's `fullscreen_vs` (bind::FULLSCREEN_WGSL, appended).

@fragment
fn composite_fs(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let ring = 2u * fr.radius_slabs + 1u;
    let p = 2u * ((u32(pos.y) * u32(fr.viewport.x) + u32(pos.x)) * ring + slab.slot);
    let sw = vec2<f32>(f32(sheet[p]), f32(sheet[p + 1u])) * SHEET_UNIT;
    if (sheet[p + 1u] != 0u) {
        sheet[p] = 0u;
        sheet[p + 1u] = 0u;
    }
    if (sw.y <= 1e-6) {
        discard;
    }
    let s = clamp(sw.x / sw.y, 0.0, 1.0);
    let x = s * f32(fr.tf_entries - 1u);
    let i0 = min(u32(floor(x)), fr.tf_entries - 2u);
    let e = mix(tf[i0], tf[i0 + 1u], x - f32(i0));
    var len = fr.delta_world;
    if (fr.perspective != 0u) {
        let ndc = vec2<f32>(pos.x / fr.viewport.x * 2.0 - 1.0, 1.0 - pos.y / fr.viewport.y * 2.0);
        len = fr.delta_world * length(vec3<f32>(ndc * fr.tan_half, 1.0));
    }
    let alpha = 1.0 - exp(-e.a * sw.y * len / fr.length_unit);
    return vec4<f32>(e.rgb * alpha, alpha);
}
