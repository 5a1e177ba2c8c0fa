// mode=passes drawn as the paper draws it (§2.3, §3.2): every pass is a rectangle per active
// tile whose fragment shader steps that pixel's ray, and rays that have ended are rejected by
// the early depth test. The paper writes their depth once every k passes, before the occlusion
// query that ends a round, so that the early z-test skips them from then on; `fs_cull` is that
// update, drawn at the start of each round here. Appended to cast.wgsl where the device can
// force early depth tests (a fragment shader that writes storage is otherwise tested late, and
// would run for every pixel of the rectangle). On a CPU backend this is what makes an ended
// ray free: a batch of pixels that fails the depth test skips the shader, where a compute
// invocation whose ray has ended still runs the step under an empty mask.

// The frame's parameters as a uniform block (the peel's group 2): a fragment shader would load
// a storage buffer lane by lane.
@group(2) @binding(0) var<uniform> tile_frame: Frame;

// Depth of the rectangles; ended rays hold 0 after `fs_cull`, every other pixel the clear, 1.
const RECT_DEPTH: f32 = 0.5;

// Two triangles over the rectangle of the active tile `slot`: corners 0 1 2 and 2 1 3 of
// (x0, y0), (x1, y0), (x0, y1), (x1, y1), whose shared diagonal the fill rule gives to one.
@vertex
fn vs_tile(@builtin(vertex_index) v: u32, @builtin(instance_index) slot: u32) -> @builtin(position) vec4<f32> {
    let r = tiles[active_tiles[slot]];
    var c = v;
    if v == 3u {
        c = 2u;
    } else if v == 4u {
        c = 1u;
    } else if v == 5u {
        c = 3u;
    }
    let x = f32(select(r.origin.x, r.end.x, (c & 1u) != 0u));
    let y = f32(select(r.origin.y, r.end.y, (c & 2u) != 0u));
    let size = vec2<f32>(f32(tile_frame.size.x), f32(tile_frame.size.y));
    return vec4<f32>(2.0 * x / size.x - 1.0, 1.0 - 2.0 * y / size.y, RECT_DEPTH, 1.0);
}

@fragment
@early_depth_test(force)
fn fs_step(@builtin(position) pos: vec4<f32>) {
    let f = tile_frame;
    let p = vec2<u32>(pos.xy);
    let t = (p.y / f.size.w) * f.counts.x + p.x / f.size.z;
    pass_step(p, t, f.size.x, step_params_of(f), ray_frame_of(f));
}

// The depth update: a pixel whose ray has ended or left its layer gets depth 0, in front of
// the rectangles; an active one 1, behind them (a ray that starts again from the next layer
// is stepped again).
@fragment
fn fs_cull(@builtin(position) pos: vec4<f32>) -> @builtin(frag_depth) f32 {
    let p = vec2<u32>(pos.xy);
    return select(1.0, 0.0, rays[p.y * tile_frame.size.x + p.x].x == NONE);
}
