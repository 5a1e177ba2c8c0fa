// Micro-benchmarks of `tetbench calibrate` (see calibrate.rs). Each entry point stresses one
// resource and does as little else as possible.

// Small triangles: triangle t lies inside one pixel of a GRID×GRID target without covering its
// centre (vertices at +0.55 / +0.95 pixel), so it is set up and rasterised but yields no
// fragment: the cost is triangle setup alone (fill is measured separately).
const GRID: u32 = 256u;

@vertex
fn tri_vs(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let t = vi / 3u;
    let k = vi % 3u;
    let cell = t % (GRID * GRID);
    let xy = vec2<f32>(f32(cell % GRID), f32(cell / GRID));
    var o = vec2<f32>(0.55, 0.55);
    if k == 1u {
        o = vec2<f32>(0.95, 0.55);
    } else if k == 2u {
        o = vec2<f32>(0.55, 0.95);
    }
    let p = (xy + o) / f32(GRID) * 2.0 - 1.0;
    return vec4<f32>(p.x, -p.y, 0.5, 1.0);
}

@fragment
fn tri_fs() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0, 0.5, 0.25, 1.0);
}

// Fill: one triangle covering the whole viewport, blended additively (as the cell-projection
// algorithms composite), so the cost is per-fragment shading + blending.
@vertex
fn fill_vs(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let k = vi % 3u;
    var p = vec2<f32>(-1.0, -1.0);
    if k == 1u {
        p = vec2<f32>(3.0, -1.0);
    } else if k == 2u {
        p = vec2<f32>(-1.0, 3.0);
    }
    return vec4<f32>(p, 0.5, 1.0);
}

@fragment
fn fill_fs() -> @location(0) vec4<f32> {
    return vec4<f32>(0.01, 0.01, 0.01, 0.01);
}

// Compute: four independent vec4 FMA chains per invocation (ILP), FMA_ITERS rounds, the result
// stored so nothing is optimised away. FLOPs per invocation = FMA_ITERS · 4 chains · 4 lanes · 2.
const FMA_ITERS: u32 = 256u;

@group(0) @binding(0) var<storage, read_write> flops_out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn fma_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let s = f32(id.x) * 1e-7;
    var a0 = vec4<f32>(s, 1.0, 2.0, 3.0);
    var a1 = a0 + 0.5;
    var a2 = a0 + 0.25;
    var a3 = a0 + 0.125;
    let b = vec4<f32>(0.999, 0.998, 0.997, 0.996);
    let c = vec4<f32>(1e-3, 2e-3, 3e-3, 4e-3);
    for (var i = 0u; i < FMA_ITERS; i++) {
        a0 = fma(a0, b, c);
        a1 = fma(a1, b, c);
        a2 = fma(a2, b, c);
        a3 = fma(a3, b, c);
    }
    flops_out[id.x] = a0 + a1 + a2 + a3;
}

// Storage copy: every invocation moves one vec4<u32> (16 bytes read, 16 written).
@group(0) @binding(1) var<storage, read> copy_src: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read_write> copy_dst: array<vec4<u32>>;

@compute @workgroup_size(64)
fn copy_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i < arrayLength(&copy_dst) {
        copy_dst[i] = copy_src[i];
    }
}
