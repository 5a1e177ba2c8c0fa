// HAVS passes (Callahan et al. 2005). Prepended by the Rust: `const K: u32 = k;`; appended:
// render_core's table_coord and kbuffer.wgsl (the k-buffer logic shared by the racy fragment pass and the race-free resolve).
//
// Faithful mode (§4, Fig. 5): vs + fs_kbuffer draw the faces in sorted order; each fragment
// reads the pixel's k-buffer from storage, runs kb_insert and writes it back. Fragments of one
// pixel may be shaded concurrently, so this read-modify-write races exactly as the paper's
// render-to-texture did; `drain` then empties each pixel's k-buffer. fs_kbuffer_counting is
// the same with the row's per-pixel counts, drawn in an untimed frame once per view.
// Race-free mode: vs + fs_append store every fragment with its submission index (its face's
// place in the sorted order) in per-pixel linked lists; `resolve_lists` sorts each list by
// submission index and streams it through the same k-buffer.

struct Uniforms {
    view_proj: mat4x4<f32>,
    // xyz: eye; w: 1 for perspective (depth = distance from the eye), 0 for orthographic.
    eye: vec4<f32>,
    // xyz: viewing direction (orthographic depth = distance along it).
    forward: vec4<f32>,
    width: u32,
    height: u32,
    // bit 0: two tags; bit 1: early ray termination.
    flags: u32,
    // Submission index of the first face of this chunk of the order buffer.
    base_face: u32,
    // Longest segment the table covers (world units), and the table's axis sizes.
    max_len: f32,
    n_s: f32,
    n_l: f32,
    node_capacity: u32,
    // Opacity at which early ray termination stops a pixel.
    et_alpha: f32,
    // First column and row of the per-pixel passes: the drain (or list resolve) covers only
    // the rectangle of the screen the mesh can reach, from here (`Camera::covered_rect`).
    rect_x0: u32,
    rect_y0: u32,
    _pad2: u32,
}

struct Pixel {
    color: vec4<f32>,
    // x: bits of the back depth of the last segment, y: fragments, z: out-of-order pops,
    // w: fragments culled after early ray termination.
    info: vec4<u32>,
}

@group(0) @binding(0) var<uniform> u: Uniforms;
// Vertices (`verts_at`): xyz, w = normalised scalar + 2 for the copies that boundary faces
// use (the paper's per-vertex boundary tag); three vertex indices per unique face
// (`faces_at`). Both are declared by the Rust (render_core::ChunkedBuffer) at bindings 11..,
// split over as many storage bindings as the mesh needs.
// This chunk of the per-frame order: face indices front to back by centroid distance.
@group(0) @binding(3) var<storage, read> order: array<u32>;
@group(0) @binding(4) var table: texture_3d<f32>;
@group(0) @binding(5) var table_sampler: sampler;
@group(0) @binding(6) var<storage, read_write> pixels: array<Pixel>;
// K entries per pixel: (v, d); d = 0 marks an empty entry (cleared with clear_buffer).
@group(0) @binding(7) var<storage, read_write> kentries: array<vec2<f32>>;
// 0: fragments, 1: out-of-order pops, 2: lists longer than MAX_LIST, 3: nodes appended,
// 4: fragments culled by early ray termination (never shaded nor looked up in the table),
// 5: fragment-race pixel updates lost to the race (shaded less counted, per pixel).
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>, 8>;
// Race-free mode: head of each pixel's list (node index + 1; 0 = empty) and the nodes
// (v bits, d bits, submission index, next). Fragment-race mode: fragments shaded per pixel.
@group(0) @binding(9) var<storage, read_write> heads: array<atomic<u32>>;
@group(0) @binding(10) var<storage, read_write> nodes: array<vec4<u32>>;

const MAX_LIST: u32 = 512u;

fn two_tags() -> bool {
    return (u.flags & 1u) != 0u;
}

fn early_termination() -> bool {
    return (u.flags & 2u) != 0u;
}

// Table lookup at texel centres: entry i of an axis of n stands for i/(n-1) (`table_coord`,
// render_core::table_texture::TABLE_WGSL).
fn segment_color(s_front: f32, s_back: f32, length: f32) -> vec4<f32> {
    let l = clamp(length / u.max_len, 0.0, 1.0);
    let ns = u.n_s;
    let nl = u.n_l;
    let uvw = vec3<f32>(table_coord(s_front, ns), table_coord(s_back, ns), table_coord(l, nl));
    return textureSampleLevel(table, table_sampler, uvw, 0.0);
}

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) v: f32,
    @location(2) @interpolate(flat) prim: u32,
}

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> VOut {
    let slot = vi / 3u;
    let face = order[slot];
    let p = verts_at(faces_at(face * 3u + vi % 3u));
    var out: VOut;
    out.pos = u.view_proj * vec4<f32>(p.xyz, 1.0);
    out.world = p.xyz;
    out.v = p.w;
    out.prim = u.base_face + slot;
    return out;
}

// The fragment as a k-buffer entry: boundary faces get tag 1 seen from outside (front-facing:
// boundary faces are wound outward) and 2 seen from inside.
fn fragment_entry(world: vec3<f32>, v: f32, front_facing: bool) -> vec2<f32> {
    let rel = world - u.eye.xyz;
    var d = dot(rel, u.forward.xyz);
    if u.eye.w > 0.5 {
        d = length(rel);
    }
    var tag = kb_tag(v);
    if tag != 0u {
        tag = select(2u, 1u, front_facing);
    }
    return vec2<f32>(kb_scalar(v) + 2.0 * f32(tag), d);
}

fn pixel_index(pos: vec4<f32>) -> u32 {
    let px = vec2<u32>(pos.xy);
    return px.y * u.width + px.x;
}

// The pixel's k-buffer as the fragment reads it: `color` and `last_back` from its record, the
// K entries from `kentries`.
fn load_entries(p: u32, color: vec4<f32>, last_back: f32) -> KState {
    var st: KState;
    st.color = color;
    st.last_back = last_back;
    st.errors = 0u;
    for (var i = 0u; i < K; i++) {
        let e = kentries[p * K + i];
        st.e[i] = select(e, vec2<f32>(0.0, KB_EMPTY), e.y == 0.0);
    }
    return st;
}

fn load_state(p: u32) -> KState {
    return load_entries(p, pixels[p].color, bitcast<f32>(pixels[p].info.x));
}

fn store_entries(p: u32, st: ptr<function, KState>) {
    for (var i = 0u; i < K; i++) {
        let e = (*st).e[i];
        kentries[p * K + i] = select(e, vec2<f32>(0.0, 0.0), e.y >= KB_EMPTY);
    }
}

// Faithful single pass, the paper's fragment program (§4): read the pixel's k-buffer, insert,
// write it back, racing with other fragments of the pixel. Early ray termination reads the
// pixel's opacity first and stops above the threshold, before the k-buffer is read or the
// table sampled. The timed frames run this; it counts nothing, so it neither reads nor keeps
// the depth of the last segment, which only the count of out-of-order pops uses (kb_emit).
@fragment
fn fs_kbuffer(in: VOut, @builtin(front_facing) front_facing: bool) -> @location(0) vec4<f32> {
    let p = pixel_index(in.pos);
    let color = pixels[p].color;
    if early_termination() && color.a >= u.et_alpha {
        return vec4<f32>(0.0);
    }
    var st = load_entries(p, color, 0.0);
    kb_insert(&st, fragment_entry(in.world, in.v, front_facing), two_tags());
    store_entries(p, &st);
    pixels[p].color = st.color;
    return vec4<f32>(0.0);
}

// The same program with the row's counts (not the paper's), run in one untimed frame per view:
// per pixel the fragments the k-buffer took in (`info.y`), its out-of-order pops (`info.z`),
// the fragments early termination culled (`info.w`), all racing like the k-buffer itself, and
// the exact atomic count of fragments shaded (`heads`), against which the drain measures the
// updates the race lost (`race_lost_updates`). Its image is the timed program's.
@fragment
fn fs_kbuffer_counting(in: VOut, @builtin(front_facing) front_facing: bool) -> @location(0) vec4<f32> {
    let p = pixel_index(in.pos);
    atomicAdd(&heads[p], 1u);
    let color = pixels[p].color;
    let info = pixels[p].info;
    if early_termination() && color.a >= u.et_alpha {
        pixels[p].info.w = info.w + 1u;
        return vec4<f32>(0.0);
    }
    var st = load_entries(p, color, bitcast<f32>(info.x));
    kb_insert(&st, fragment_entry(in.world, in.v, front_facing), two_tags());
    store_entries(p, &st);
    pixels[p].color = st.color;
    pixels[p].info = vec4<u32>(bitcast<u32>(st.last_back), info.y + 1u, info.z + st.errors, info.w);
    return vec4<f32>(0.0);
}

// Race-free mode, pass 1: append the fragment with its submission index.
@fragment
fn fs_append(in: VOut, @builtin(front_facing) front_facing: bool) -> @location(0) vec4<f32> {
    let p = pixel_index(in.pos);
    let f = fragment_entry(in.world, in.v, front_facing);
    let idx = atomicAdd(&counters[3], 1u);
    if idx < u.node_capacity {
        let next = atomicExchange(&heads[p], idx + 1u);
        nodes[idx] = vec4<u32>(bitcast<u32>(f.x), bitcast<u32>(f.y), in.prim, next);
    }
    return vec4<f32>(0.0);
}

// Faithful mode, screen pass after the last face: drain what each k-buffer still holds.
@compute @workgroup_size(8, 8)
fn drain(@builtin(global_invocation_id) g: vec3<u32>) {
    let x = g.x + u.rect_x0;
    let y = g.y + u.rect_y0;
    if x >= u.width || y >= u.height {
        return;
    }
    let p = y * u.width + x;
    var st = load_state(p);
    if !(early_termination() && st.color.a >= u.et_alpha) {
        kb_drain(&st, two_tags());
    }
    pixels[p].color = st.color;
    let info = pixels[p].info;
    // Only pixels with something to count touch the shared counters: on a small mesh most
    // pixels are empty, and three contended atomics per pixel of the screen were a fixed cost
    // of every frame (docs/profile.md).
    if info.y != 0u {
        atomicAdd(&counters[0], info.y);
    }
    if info.z + st.errors != 0u {
        atomicAdd(&counters[1], info.z + st.errors);
    }
    if info.w != 0u {
        atomicAdd(&counters[4], info.w);
    }
    // Every fragment shaded adds one to info.y or info.w unless another fragment's write of
    // the pixel overwrote it.
    let shaded = atomicLoad(&heads[p]);
    if shaded > info.y + info.w {
        atomicAdd(&counters[5], shaded - info.y - info.w);
    }
}

fn node_entry(n: vec4<u32>) -> vec2<f32> {
    return vec2<f32>(bitcast<f32>(n.x), bitcast<f32>(n.y));
}

// Race-free mode, pass 2: each pixel's fragments in submission order through the k-buffer.
@compute @workgroup_size(8, 8)
fn resolve_lists(@builtin(global_invocation_id) g: vec3<u32>) {
    let x = g.x + u.rect_x0;
    let y = g.y + u.rect_y0;
    if x >= u.width || y >= u.height {
        return;
    }
    let p = y * u.width + x;
    var st: KState;
    st.color = vec4<f32>(0.0);
    st.last_back = 0.0;
    st.errors = 0u;
    for (var i = 0u; i < K; i++) {
        st.e[i] = vec2<f32>(0.0, KB_EMPTY);
    }
    let et = early_termination();
    let two = two_tags();
    var ids: array<u32, MAX_LIST>;
    var n = 0u;
    var culled = 0u;
    var cur = atomicLoad(&heads[p]);
    while cur != 0u {
        if n < MAX_LIST {
            ids[n] = cur - 1u;
        }
        n += 1u;
        cur = nodes[cur - 1u].w;
    }
    if n <= MAX_LIST {
        // The list is last-in first-out: reversed it is nearly in submission order, so an
        // insertion sort by submission index costs little more than a pass.
        for (var i = 0u; i < n / 2u; i++) {
            let t = ids[i];
            ids[i] = ids[n - 1u - i];
            ids[n - 1u - i] = t;
        }
        for (var i = 1u; i < n; i++) {
            let id = ids[i];
            let key = nodes[id].z;
            var j = i;
            while j > 0u && nodes[ids[j - 1u]].z > key {
                ids[j] = ids[j - 1u];
                j -= 1u;
            }
            ids[j] = id;
        }
        for (var i = 0u; i < n; i++) {
            if et && st.color.a >= u.et_alpha {
                culled = n - i;
                break;
            }
            kb_insert(&st, node_entry(nodes[ids[i]]), two);
        }
    } else {
        // Deeper pixels: select the next submission index by walking the list each time
        // (a face covers a pixel centre at most once, so indices are distinct).
        atomicAdd(&counters[2], 1u);
        var last = 0u;
        var first = true;
        for (var step = 0u; step < n; step++) {
            var best = 0xffffffffu;
            var best_id = 0u;
            var c = atomicLoad(&heads[p]);
            while c != 0u {
                let nd = nodes[c - 1u];
                if (first || nd.z > last) && nd.z <= best {
                    best = nd.z;
                    best_id = c - 1u;
                }
                c = nd.w;
            }
            first = false;
            last = best;
            if et && st.color.a >= u.et_alpha {
                culled = n - step;
                break;
            }
            kb_insert(&st, node_entry(nodes[best_id]), two);
        }
    }
    if !(et && st.color.a >= u.et_alpha) {
        kb_drain(&st, two);
    }
    pixels[p].color = st.color;
    atomicAdd(&counters[0], n - culled);
    atomicAdd(&counters[1], st.errors);
    atomicAdd(&counters[4], culled);
}
