// Phase 3 of §3.2: per pixel, the ray's current cell (the paper's Table 2: tet (t_u, t_v), λ,
// s(e + λr)) and its colour; each step crosses one tet — exit face = smallest λ among faces with
// a positive denominator (§2.2) — and composites that segment front to back (Eq. 3) with the
// 3D pre-integrated table (s_front, s_back, length / longest edge) or the 2D one (fixed length,
// scaled by length as the paper's code does). A ray that leaves the mesh continues from its
// next peeling layer: in mode=passes once its tile's rays have all left their layer
// (`load_layer`, §3.2 phase 3a), in mode=loop at once. `step` is one pass (mode=passes),
// `run_loop` loops to the end (mode=loop).

// Statistics slots (atomics).
const STAT_ENTERED: u32 = 0u;
const STAT_TERMINATED: u32 = 1u;
const STAT_STALLED: u32 = 2u;
const STAT_DROPPED: u32 = 3u;
const STAT_SKIPPED: u32 = 4u;
const STAT_STEPS: u32 = 5u;
const STAT_MAX_STEPS: u32 = 6u;
// Carry of STAT_STEPS: the sum over all rays is a 64-bit count (high word here), since a large
// mesh at a large viewport can cross more than 2^32 tets per frame.
const STAT_STEPS_HIGH: u32 = 7u;

struct TileRect {
    origin: vec2<u32>,
    end: vec2<u32>,
}

struct PassParams {
    // 1 on the pass that ends a round: rays still active are counted per tile.
    count: u32,
}

@group(1) @binding(0) var<storage, read_write> rays: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> colours: array<vec4<f32>>;
// (peel layer the ray is in, or ENDED once it has ended; steps taken)
@group(1) @binding(2) var<storage, read_write> aux: array<vec2<u32>>;
@group(1) @binding(3) var layers: texture_2d_array<u32>;
@group(1) @binding(4) var table: texture_3d<f32>;
@group(1) @binding(5) var<storage, read_write> tile_counts: array<atomic<u32>>;
@group(1) @binding(6) var<storage, read_write> stats: array<atomic<u32>>;
@group(1) @binding(7) var<storage, read> tiles: array<TileRect>;
// The tiles that still have active rays; workgroup z picks one.
@group(1) @binding(8) var<storage, read> active_tiles: array<u32>;
@group(1) @binding(9) var<storage, read> pass_params: PassParams;

@group(1) @binding(10) var table_sampler: sampler;

// What a step reads of the frame's parameters, loaded once at the top of an entry point: there
// every invocation is active and the address the same, so a CPU backend loads it once, where
// a storage load inside the step loop's divergent control flow runs lane by lane.
struct StepParams {
    flags: u32,
    max_steps: u32,
    layers: u32,
    et_alpha: f32,
    peel_bias: f32,
    inv_table_length: f32,
    table_entries: u32,
    table_lengths: u32,
}

fn step_params_of(f: Frame) -> StepParams {
    return StepParams(
        f.counts.w,
        f.counts.z,
        f.counts.y,
        f.misc.z,
        f.misc.y,
        f.misc.w,
        f.table.x,
        f.table.y,
    );
}

fn step_params() -> StepParams {
    return step_params_of(frame);
}

// One filtered sample of the pre-integration table (render_core::table_texture; `table_coord`
// from its TABLE_WGSL). The 2D table is a 3D texture of one length: both tables take the same
// sample, and selects (not branches) pick the coordinate and the scaling, since a SIMD backend
// that runs both sides of a branch under a mask (llvmpipe) would otherwise sample twice a step.
fn lookup(s_f: f32, s_b: f32, len: f32, sp: StepParams) -> vec4<f32> {
    let n = f32(sp.table_entries);
    let u = table_coord(s_f, n);
    let v = table_coord(s_b, n);
    let is_3d = (sp.flags & FLAG_TABLE3D) != 0u;
    let w = select(0.5, table_coord(len * sp.inv_table_length, f32(sp.table_lengths)), is_3d);
    let c = textureSampleLevel(table, table_sampler, vec3<f32>(u, v, w), 0.0);
    // The 2D table holds a segment of the fixed length; the paper's code scales by length
    // (§2.2). The positive control (FLAG_UNSCALED) takes the entry as it stands, as the 3D
    // table's.
    let as_is = is_3d || (sp.flags & FLAG_UNSCALED) != 0u;
    return select(min(c * (len * sp.inv_table_length), vec4<f32>(1.0)), c, as_is);
}

struct State {
    tet: vec2<u32>,
    lambda: f32,
    s: f32,
    layer: u32,
    steps: u32,
    colour: vec4<f32>,
    // Layer entries passed over because they lie behind the ray (STAT_SKIPPED) in this
    // invocation; `count_end` adds them to the statistics.
    skipped: u32,
}

fn load(i: u32) -> State {
    let r = rays[i];
    let a = aux[i];
    var st: State;
    st.tet = r.xy;
    st.lambda = bitcast<f32>(r.z);
    st.s = bitcast<f32>(r.w);
    st.layer = a.x;
    st.steps = a.y;
    st.colour = colours[i];
    st.skipped = 0u;
    return st;
}

fn store(i: u32, st: State) {
    rays[i] = vec4<u32>(st.tet, bitcast<u32>(st.lambda), bitcast<u32>(st.s));
    aux[i] = vec2<u32>(st.layer, st.steps);
    colours[i] = st.colour;
}

// The layer of a ray that has ended (`aux.x`): a ray at tet NONE with any other layer has left
// its layer and waits for `load_layer`.
const ENDED: u32 = 0xffffffffu;

// Why `advance` ended a ray; ACTIVE: it did not.
const ACTIVE: u32 = 0u;
const END_LEFT: u32 = 1u;
const END_TERMINATED: u32 = 2u;
const END_STALLED: u32 = 3u;

// The statistics of a ray that ended (`end` ≠ ACTIVE) and the skipped entries of any ray,
// counted once after its steps. A CPU backend runs an atomic lane by lane, and llvmpipe (Mesa
// 22.3's gallivm) runs the body of every `if` under a mask instead of branching around it, so
// atomics inside the step's branches cost their lane-by-lane loop on every step of every ray.
fn count_end(st: ptr<function, State>, end: u32) {
    if (*st).skipped != 0u {
        atomicAdd(&stats[STAT_SKIPPED], (*st).skipped);
    }
    if end == ACTIVE {
        return;
    }
    (*st).tet = vec2<u32>(NONE, NONE);
    (*st).layer = ENDED;
    if end == END_TERMINATED {
        atomicAdd(&stats[STAT_TERMINATED], 1u);
    } else if end == END_STALLED {
        atomicAdd(&stats[STAT_STALLED], 1u);
    }
    let before = atomicAdd(&stats[STAT_STEPS], (*st).steps);
    if before > 0xffffffffu - (*st).steps {
        atomicAdd(&stats[STAT_STEPS_HIGH], 1u);
    }
    atomicMax(&stats[STAT_MAX_STEPS], (*st).steps);
}

// One ray step (phase 3a); returns ACTIVE or why the ray ended. A ray that leaves the mesh
// is left at tet NONE and still ACTIVE: `next_layer` continues it.
fn advance(st: ptr<function, State>, ray: Ray, sp: StepParams) -> u32 {
    let ex = exit_of((*st).tet, ray.o, ray.d, (*st).lambda);
    let seg = lookup((*st).s, ex.s, ex.lambda - (*st).lambda, sp);
    (*st).colour += (1.0 - (*st).colour.a) * seg;
    (*st).steps += 1u;
    (*st).tet = ex.next;
    (*st).lambda = ex.lambda;
    (*st).s = ex.s;
    if (sp.flags & FLAG_ET) != 0u && (*st).colour.a >= sp.et_alpha {
        return END_TERMINATED;
    }
    if (*st).steps >= sp.max_steps {
        return END_STALLED;
    }
    return ACTIVE;
}

// A ray that left the mesh continues from the next peeling layer that lies ahead of its exit
// (§2.4): one layer a call; an entry behind the ray (rare: `skipped`) leaves tet NONE for the
// next call. Kept out of the step loop's body: llvmpipe branches around no `if` (it masks),
// so inside the loop this ran on every step, about an eighth of a step's time.
fn next_layer(st: ptr<function, State>, p: vec2<u32>, sp: StepParams) -> u32 {
    (*st).layer += 1u;
    if (*st).layer >= sp.layers {
        return END_LEFT;
    }
    let e = textureLoad(layers, vec2<i32>(p), i32((*st).layer), 0);
    if e.x == NONE {
        return END_LEFT;
    }
    let l = bitcast<f32>(e.z);
    if l >= (*st).lambda - sp.peel_bias {
        (*st).tet = e.xy;
        (*st).lambda = l;
        (*st).s = bitcast<f32>(e.w);
    } else {
        (*st).skipped += 1u;
    }
    return ACTIVE;
}

fn tile_of(p: vec2<u32>) -> u32 {
    return (p.y / frame.size.w) * frame.counts.x + p.x / frame.size.z;
}

// Per frame: every ray starts at its first-layer entry; colour cleared; active rays counted
// per tile (so an empty tile never runs a pass).
@compute @workgroup_size(8, 8)
fn init(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = gid.xy;
    if p.x >= frame.size.x || p.y >= frame.size.y {
        return;
    }
    let i = p.y * frame.size.x + p.x;
    colours[i] = vec4<f32>(0.0);
    var e = vec4<u32>(NONE);
    if frame.counts.y > 0u {
        e = textureLoad(layers, vec2<i32>(p), 0, 0);
    }
    rays[i] = e;
    // A pixel no ray enters has ended (no later layer holds it either: peeling goes front to
    // back per pixel).
    aux[i] = vec2<u32>(select(0u, ENDED, e.x == NONE), 0u);
    if e.x != NONE {
        atomicAdd(&tile_counts[tile_of(p)], 1u);
        atomicAdd(&stats[STAT_ENTERED], 1u);
    }
    if (frame.counts.w & FLAG_COUNT_DROPPED) != 0u {
        let d = textureLoad(layers, vec2<i32>(p), i32(frame.table.z), 0);
        if d.x != NONE {
            atomicAdd(&stats[STAT_DROPPED], 1u);
        }
    }
}

// The pixel of an invocation: workgroup z is a slot of the active-tile list, x and y cover
// that tile's rectangle (all active tiles of a pass run in one dispatch, as the paper draws one
// rectangle per tile in a pass). Returns the tile index, or NONE outside the rectangle.
fn tile_pixel(wg: vec3<u32>, lid: vec3<u32>, p: ptr<function, vec2<u32>>) -> u32 {
    let t = active_tiles[wg.z];
    let r = tiles[t];
    // Z order inside the 8×8 group: 8 consecutive invocations (one SIMD batch of a CPU
    // backend) cover a 4×2 block instead of a row of 8, so their rays are more alike.
    let idx = lid.y * 8u + lid.x;
    let m = vec2<u32>(
        (idx & 1u) | ((idx >> 1u) & 2u) | ((idx >> 2u) & 4u),
        ((idx >> 1u) & 1u) | ((idx >> 2u) & 2u) | ((idx >> 3u) & 4u),
    );
    *p = r.origin + wg.xy * 8u + m;
    if (*p).x >= r.end.x || (*p).y >= r.end.y {
        return NONE;
    }
    return t;
}

// One pass of mode=passes for the ray of pixel `p` in tile `t`: one step (§2.3). A ray that
// leaves the mesh waits at tet NONE for its tile's next layer (`load_layer`). On the pass that
// ends a round the rays still active are counted per tile (the paper's occlusion query, here an
// atomic count).
fn pass_step(p: vec2<u32>, t: u32, width: u32, sp: StepParams, rf: RayFrame) {
    let i = p.y * width + p.x;
    if rays[i].x == NONE {
        return;
    }
    var st = load(i);
    let ray = ray_through(rf, vec2<f32>(p) + 0.5);
    let end = advance(&st, ray, sp);
    count_end(&st, end);
    store(i, st);
    if end == ACTIVE && st.tet.x != NONE && pass_params.count != 0u {
        atomicAdd(&tile_counts[t], 1u);
    }
}

// mode=passes, once every ray of a tile has left its layer (§3.2 phase 3a: the next peeling
// layer is recovered and the passes restart from it): every waiting ray of the listed tiles
// moves to its next entry ahead of it, or ends where none is left; the rays that start again
// are counted per tile (a tile at zero is done).
@compute @workgroup_size(8, 8)
fn load_layer(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let sp = step_params();
    var p: vec2<u32>;
    let t = tile_pixel(wg, lid, &p);
    if t == NONE {
        return;
    }
    let i = p.y * frame.size.x + p.x;
    if rays[i].x != NONE || aux[i].x == ENDED {
        return;
    }
    var st = load(i);
    var end = ACTIVE;
    loop {
        if end != ACTIVE || st.tet.x != NONE {
            break;
        }
        end = next_layer(&st, p, sp);
    }
    count_end(&st, end);
    store(i, st);
    if end == ACTIVE {
        atomicAdd(&tile_counts[t], 1u);
    }
}

// mode=passes as a compute pass (adapters without forced early depth tests): every pixel of
// the listed tiles runs `pass_step`; a ray that has ended returns at its first test, but a CPU
// backend still runs the step under an empty mask (it branches around no `if`).
@compute @workgroup_size(8, 8)
fn step(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let sp = step_params();
    let rf = ray_frame();
    let width = frame.size.x;
    var p: vec2<u32>;
    let t = tile_pixel(wg, lid, &p);
    if t == NONE {
        return;
    }
    pass_step(p, t, width, sp, rf);
}

// mode=loop: one dispatch over the non-empty tiles; each ray steps until it leaves the last
// layer.
@compute @workgroup_size(8, 8)
fn run_loop(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let sp = step_params();
    let rf = ray_frame();
    let width = frame.size.x;
    var p: vec2<u32>;
    let t = tile_pixel(wg, lid, &p);
    if t == NONE {
        return;
    }
    let i = p.y * width + p.x;
    if rays[i].x == NONE {
        return;
    }
    var st = load(i);
    let ray = ray_through(rf, vec2<f32>(p) + 0.5);
    var end = ACTIVE;
    loop {
        // The tets of one peeling layer's segment of the ray.
        loop {
            if st.tet.x == NONE {
                break;
            }
            end = advance(&st, ray, sp);
            if end != ACTIVE {
                break;
            }
        }
        if end != ACTIVE {
            break;
        }
        end = next_layer(&st, p, sp);
        if end != ACTIVE {
            break;
        }
    }
    count_end(&st, end);
    store(i, st);
}
