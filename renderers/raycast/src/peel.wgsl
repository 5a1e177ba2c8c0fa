// Phases 1 and 2 of §3.2: the front-facing boundary faces are rasterised (back faces culled,
// Z-buffer on), each vertex carrying its tet's (binding, index); the fragment shader computes
// the entry parameter λ and the scalar there in object coordinates. A peeling layer (phase 2)
// discards every fragment not farther than the previous layer's λ plus a bias, so the Z-buffer
// keeps the next boundary entry behind it. Depth is λ / λ_far, so the Z order is the λ order.

@group(1) @binding(0) var prev_layer: texture_2d<u32>;
// The frame's parameters again, as a uniform block: a CPU backend loads a storage buffer in a
// fragment shader lane by lane even where every lane reads the same address (llvmpipe takes
// its one-load path for storage only where invocation 0 is known to be active, never in a
// fragment shader), and a uniform block once.
@group(2) @binding(0) var<uniform> peel_frame: Frame;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) tet: vec2<u32>,
}

@vertex
fn vs_face(@location(0) pos: vec3<f32>, @location(1) tet: vec2<u32>) -> VOut {
    var out: VOut;
    out.pos = peel_frame.view_proj * vec4<f32>(pos, 1.0);
    out.tet = tet;
    return out;
}

struct FOut {
    @location(0) cell: vec4<u32>,
    @builtin(frag_depth) depth: f32,
}

fn first_hit(in: VOut) -> FOut {
    let ray = ray_through(ray_frame_of(peel_frame), in.pos.xy);
    let lambda = entry_lambda(in.tet, ray.o, ray.d);
    let s = scalar_at(in.tet, ray.o + lambda * ray.d);
    var out: FOut;
    out.cell = vec4<u32>(in.tet, bitcast<u32>(lambda), bitcast<u32>(s));
    out.depth = clamp(lambda * peel_frame.misc.x, 0.0, 1.0);
    return out;
}

// Phase 1: the first visible boundary face per pixel.
@fragment
fn fs_first(in: VOut) -> FOut {
    return first_hit(in);
}

// Phase 2: the next boundary entry behind the previous layer's.
@fragment
fn fs_peel(in: VOut) -> FOut {
    let prev = textureLoad(prev_layer, vec2<i32>(in.pos.xy), 0);
    if prev.x == NONE {
        discard;
    }
    let out = first_hit(in);
    if bitcast<f32>(out.cell.z) <= bitcast<f32>(prev.z) + peel_frame.misc.y {
        discard;
    }
    return out;
}

// `Pipelines::more`: render_core's `fullscreen_vs` (bind::FULLSCREEN_WGSL, appended), tested
// against the stencil only (the peeling pass's count of candidates per pixel) under an
// occlusion query; it writes nothing.
@fragment
fn fs_nothing() -> @location(0) vec4<u32> {
    return vec4<u32>(0u);
}
