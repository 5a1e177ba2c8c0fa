// The k-buffer of HAVS (Callahan et al. 2005, §3.2 and §4), shared by the single-pass fragment
// shader (faithful, racy) and the race-free compute resolve. Its CPU twin is kbuffer.rs: keep
// the two in step.
//
// The including module defines `const K: u32` (entries per pixel) and
// `fn segment_color(s_front: f32, s_back: f32, length: f32) -> vec4<f32>` (the lookup in the
// 3D pre-integrated table).
//
// An entry is (v, d): v = s + 2·tag with s the normalised scalar in [0, 1] and tag 0 interior,
// 1 entry (front-facing boundary), 2 exit (back-facing boundary); d the distance along the
// pixel's ray in world units. An empty entry has d = KB_EMPTY.

const KB_EMPTY: f32 = 3.0e38;

struct KState {
    e: array<vec2<f32>, K>,
    color: vec4<f32>,
    last_back: f32,
    errors: u32,
}

fn kb_tag(v: f32) -> u32 {
    // v lies in [2·tag, 2·tag + 1] up to interpolation error: round to the nearest tag.
    return u32(max(round((v - 0.5) * 0.5), 0.0));
}

fn kb_scalar(v: f32) -> f32 {
    return clamp(v - 2.0 * f32(kb_tag(v)), 0.0, 1.0);
}

// §4 holes. Single tag (what the paper shipped): a segment between two boundary fragments is a
// gap. Two tags: only exit → entry is a gap.
fn kb_composites(front: vec2<f32>, back: vec2<f32>, two_tags: bool) -> bool {
    let tf = kb_tag(front.x);
    let tb = kb_tag(back.x);
    if two_tags {
        return !(tf == 2u && tb == 1u);
    }
    return !(tf != 0u && tb != 0u);
}

fn kb_emit(st: ptr<function, KState>, front: vec2<f32>, back: vec2<f32>, two_tags: bool) {
    if front.y < (*st).last_back {
        (*st).errors += 1u;
    }
    (*st).last_back = back.y;
    if kb_composites(front, back, two_tags) {
        let c = segment_color(kb_scalar(front.x), kb_scalar(back.x), back.y - front.y);
        (*st).color += (1.0 - (*st).color.a) * c;
    }
}

fn kb_closest(st: ptr<function, KState>) -> u32 {
    var best = K;
    var bd = KB_EMPTY;
    for (var i = 0u; i < K; i++) {
        if (*st).e[i].y < bd {
            bd = (*st).e[i].y;
            best = i;
        }
    }
    return best;
}

// One incoming fragment: a free entry takes it; otherwise the closest of the K + 1 candidates
// is popped and composited against the closest of the K that remain. Written with selects
// over every entry, and no index computed at run time, so that a compiler can keep the K
// entries in registers: a software rasteriser keeps an array indexed at run time in memory
// and reaches it lane by lane (docs/roofline.md). The same choices as a search that stops at
// the first free entry and indexes the one it finds: the first free entry, the first of the
// closest, ties to the lower index.
fn kb_insert(st: ptr<function, KState>, f: vec2<f32>, two_tags: bool) {
    var placed = false;
    for (var i = 0u; i < K; i++) {
        let take = !placed && (*st).e[i].y >= KB_EMPTY;
        (*st).e[i] = select((*st).e[i], f, take);
        placed = placed || take;
    }
    if placed {
        return;
    }
    var imin = K;
    var dmin = f.y;
    for (var i = 0u; i < K; i++) {
        let closer = (*st).e[i].y < dmin;
        dmin = select(dmin, (*st).e[i].y, closer);
        imin = select(imin, i, closer);
    }
    var popped = f;
    for (var i = 0u; i < K; i++) {
        let hit = i == imin;
        popped = select(popped, (*st).e[i], hit);
        (*st).e[i] = select((*st).e[i], f, hit);
    }
    // Every entry is full here: the closest is the first of the smallest depth.
    var back = (*st).e[0];
    for (var i = 1u; i < K; i++) {
        back = select(back, (*st).e[i], (*st).e[i].y < back.y);
    }
    kb_emit(st, popped, back, two_tags);
}

// The screen pass after the last face: pop the remaining entries in order.
fn kb_drain(st: ptr<function, KState>, two_tags: bool) {
    loop {
        let i = kb_closest(st);
        if i >= K {
            break;
        }
        let front = (*st).e[i];
        (*st).e[i] = vec2<f32>(0.0, KB_EMPTY);
        let j = kb_closest(st);
        if j >= K {
            break;
        }
        kb_emit(st, front, (*st).e[j], two_tags);
    }
}
