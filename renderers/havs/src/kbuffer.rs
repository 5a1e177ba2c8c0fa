//! The CPU twin of the k-buffer (HAVS §3.2, §4): the exact logic of `kbuffer.wgsl`, used by the
//! tests, by the A-buffer analysis of Table 2 and by the CPU model of the race-free renderer.
//!
//! A pixel keeps `k` entries (scalar, depth). An incoming fragment goes into a free entry if
//! there is one; otherwise, of the `k + 1` candidates (the entries and the fragment), the closest
//! is popped and becomes the front of a ray segment whose back is the closest of the `k` that
//! remain (the paper composites "the two closest"); the segment is looked up in the
//! pre-integrated table with (s_front, s_back, Δd) and composited front to back. After the last
//! face the remaining entries are drained in order.
//!
//! Exactness: a fragment stream gives exactly the segments of the sorted stream iff every
//! fragment of sorted rank `r ≥ 1` arrives at input position ≤ `r + k − 1` (and rank 0 at
//! position ≤ `k`): [`k_needed`] is the smallest `k` meeting that. Whenever the popped fragment
//! lies in front of the back of the previous segment, a segment was wrong; the twin and the GPU
//! count those events (`out_of_order`), which happens iff the output is not exact.

/// How a fragment's face relates to the mesh boundary (HAVS §4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Tag {
    /// An interior face (two incident tets).
    Interior = 0,
    /// A boundary face seen from outside: the ray enters the mesh here.
    Entry = 1,
    /// A boundary face seen from inside: the ray leaves the mesh here.
    Exit = 2,
}

impl Tag {
    pub fn from_index(i: u32) -> Tag {
        match i {
            1 => Tag::Entry,
            2 => Tag::Exit,
            _ => Tag::Interior,
        }
    }
    pub fn is_boundary(self) -> bool {
        self != Tag::Interior
    }
}

/// Which segments between boundary fragments are gaps (rays leaving and re-entering the mesh).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TagScheme {
    /// What the paper shipped (§4): one "boundary" tag; a segment between two boundary
    /// fragments is taken to be outside the mesh. Wrong for a tet whose entry and exit faces
    /// are both on the boundary (thin parts), whose segment is then dropped.
    Single,
    /// The paper's two-tag proposal: entry (front-facing boundary) and exit (back-facing
    /// boundary); only the segment from an exit to an entry is a gap. Exact.
    Two,
}

impl TagScheme {
    /// Whether the segment (front, back) lies inside the mesh and is composited.
    pub fn composites(self, front: Tag, back: Tag) -> bool {
        match self {
            TagScheme::Single => !(front.is_boundary() && back.is_boundary()),
            TagScheme::Two => !(front == Tag::Exit && back == Tag::Entry),
        }
    }
}

/// One fragment: normalised scalar, distance along the pixel's ray (world units), tag.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fragment {
    pub scalar: f32,
    pub depth: f32,
    pub tag: Tag,
}

/// A ray segment the k-buffer composites (or drops as a gap: `inside == false`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    pub front: Fragment,
    pub back: Fragment,
    pub inside: bool,
}

/// The per-pixel k-buffer of the twin.
#[derive(Debug, Clone)]
pub struct KBuffer {
    k: usize,
    scheme: TagScheme,
    entries: Vec<Fragment>,
    last_back: f32,
    /// Pops that landed in front of the previous segment's back: each marks a wrong segment.
    pub out_of_order: u32,
}

impl KBuffer {
    pub fn new(k: usize, scheme: TagScheme) -> KBuffer {
        assert!(k >= 1, "a k-buffer needs at least one entry");
        KBuffer {
            k,
            scheme,
            entries: Vec::with_capacity(k),
            last_back: f32::NEG_INFINITY,
            out_of_order: 0,
        }
    }

    pub fn k(&self) -> usize {
        self.k
    }

    /// Feeds one fragment; returns the segment it produced, if the buffer was full.
    pub fn insert(&mut self, f: Fragment) -> Option<Segment> {
        if self.entries.len() < self.k {
            self.entries.push(f);
            return None;
        }
        // Closest of the k + 1 candidates; the incoming fragment wins ties last (as the shader:
        // strict `<` over the stored entries, starting from the fragment).
        let mut imin = None;
        let mut dmin = f.depth;
        for (i, e) in self.entries.iter().enumerate() {
            if e.depth < dmin {
                dmin = e.depth;
                imin = Some(i);
            }
        }
        let popped = match imin {
            Some(i) => std::mem::replace(&mut self.entries[i], f),
            None => f,
        };
        let back = *self.closest().expect("k >= 1 entries remain");
        Some(self.emit(popped, back))
    }

    fn closest(&self) -> Option<&Fragment> {
        let mut best: Option<&Fragment> = None;
        for e in &self.entries {
            if best.is_none_or(|b| e.depth < b.depth) {
                best = Some(e);
            }
        }
        best
    }

    fn emit(&mut self, front: Fragment, back: Fragment) -> Segment {
        if front.depth < self.last_back {
            self.out_of_order += 1;
        }
        self.last_back = back.depth;
        Segment {
            front,
            back,
            inside: self.scheme.composites(front.tag, back.tag),
        }
    }

    /// After the last face: pops the remaining entries in order (the screen pass).
    pub fn drain(&mut self, out: &mut Vec<Segment>) {
        while !self.entries.is_empty() {
            let (i, _) =
                self.entries
                    .iter()
                    .enumerate()
                    .fold((0, f32::INFINITY), |(bi, bd), (i, e)| {
                        if e.depth < bd {
                            (i, e.depth)
                        } else {
                            (bi, bd)
                        }
                    });
            let front = self.entries.swap_remove(i);
            match self.closest() {
                Some(&back) => {
                    let s = self.emit(front, back);
                    out.push(s);
                }
                None => break,
            }
        }
    }

    /// Runs a whole pixel's fragment stream (arrival order) and drains.
    pub fn run(k: usize, scheme: TagScheme, stream: &[Fragment]) -> (Vec<Segment>, u32) {
        let mut kb = KBuffer::new(k, scheme);
        let mut out = Vec::with_capacity(stream.len());
        for &f in stream {
            if let Some(s) = kb.insert(f) {
                out.push(s);
            }
        }
        kb.drain(&mut out);
        (out, kb.out_of_order)
    }
}

/// The segments an exact sort gives: consecutive pairs of the stream sorted by depth
/// (ties kept in arrival order).
pub fn exact_segments(scheme: TagScheme, stream: &[Fragment]) -> Vec<Segment> {
    let mut sorted = stream.to_vec();
    sorted.sort_by(|a, b| a.depth.total_cmp(&b.depth));
    sorted
        .windows(2)
        .map(|w| Segment {
            front: w[0],
            back: w[1],
            inside: scheme.composites(w[0].tag, w[1].tag),
        })
        .collect()
}

/// The smallest k for which the k-buffer outputs a pixel's stream (depths in arrival order)
/// exactly: max(1, pos(rank 0), max over ranks r ≥ 1 of pos(r) − r + 1), ranks by depth with
/// ties in arrival order.
pub fn k_needed(depths: &[f32]) -> usize {
    if depths.len() <= 1 {
        return 1;
    }
    let mut by_rank: Vec<u32> = (0..depths.len() as u32).collect();
    by_rank.sort_by(|&a, &b| {
        depths[a as usize]
            .total_cmp(&depths[b as usize])
            .then(a.cmp(&b))
    });
    let mut k = (by_rank[0] as usize).max(1);
    for (r, &pos) in by_rank.iter().enumerate().skip(1) {
        let pos = pos as usize;
        if pos + 1 > r {
            k = k.max(pos + 1 - r);
        }
    }
    k
}

/// The k of HAVS Table 2 as the paper measures it (§5.2): each fragment, in arrival order, is
/// inserted into an ordered A-buffer and the depth of the insertion (how many fragments already
/// there lie behind it) is recorded; the pixel's k is the deepest insertion plus one, the one
/// more entry that compositing needs (§3.2: a k-nearly sorted stream needs k + 1 entries).
/// Ties insert after equal depths. Never below [`k_needed`]: a fragment of sorted rank r that
/// arrives at position p passes at least p − r fragments, so a k-buffer of this size is exact too.
pub fn insertion_k(depths: &[f32]) -> usize {
    let mut sorted: Vec<f32> = Vec::with_capacity(depths.len());
    let mut deepest = 0;
    for &d in depths {
        let at = sorted.partition_point(|&x| x <= d);
        deepest = deepest.max(sorted.len() - at);
        sorted.insert(at, d);
    }
    deepest + 1
}

/// Front-to-back compositing of premultiplied RGBA (the "over" operator seen from the front).
#[inline]
pub fn composite_front_to_back(acc: &mut [f32; 4], seg: [f32; 4]) {
    let t = 1.0 - acc[3];
    for c in 0..4 {
        acc[c] += t * seg[c];
    }
}

/// Opacity beyond which a pixel is treated as opaque by early ray termination: half an 8-bit
/// step of what lies behind can still be lost, below what an 8-bit image shows.
pub const EARLY_TERMINATION_ALPHA: f32 = 1.0 - 1.0 / 512.0;

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn frag(d: f32) -> Fragment {
        Fragment {
            scalar: d / 100.0,
            depth: d,
            tag: Tag::Interior,
        }
    }

    /// A sequence of `n` distinct depths in which each element of sorted rank r arrives at
    /// position ≤ r + max_delay: sort by the perturbed key r + u·max_delay·(1 − ε).
    fn nearly_sorted(n: usize, max_delay: usize, u: &[f64]) -> Vec<f32> {
        let mut keyed: Vec<(f64, f32)> = (0..n)
            .map(|r| {
                (
                    r as f64 + u[r] * max_delay as f64 * 0.999,
                    (r as f32 + 1.0) * 0.5,
                )
            })
            .collect();
        keyed.sort_by(|a, b| a.0.total_cmp(&b.0));
        keyed.into_iter().map(|(_, d)| d).collect()
    }

    proptest! {
        /// Fed any stream in which no fragment is more than k − 1 places late, the k-buffer
        /// outputs exactly the segments of the sorted stream and reports nothing.
        #[test]
        fn nearly_sorted_streams_come_out_exact(k in 1usize..17, n in 0usize..120,
                                                u in proptest::collection::vec(0.0f64..1.0, 120)) {
            let depths = nearly_sorted(n, k - 1, &u);
            prop_assert!(k_needed(&depths) <= k);
            let stream: Vec<Fragment> = depths.iter().map(|&d| frag(d)).collect();
            let (segs, errors) = KBuffer::run(k, TagScheme::Two, &stream);
            prop_assert_eq!(errors, 0);
            prop_assert_eq!(segs, exact_segments(TagScheme::Two, &stream));
        }

        /// For any stream, k_needed is the smallest k that is exact, and the out-of-order count
        /// is non-zero exactly when the output is wrong.
        #[test]
        fn k_needed_is_tight_and_errors_are_detected(depths in proptest::collection::hash_set(0u32..10_000, 0..40)) {
            let depths: Vec<f32> = depths.into_iter().map(|d| d as f32).collect();
            let stream: Vec<Fragment> = depths.iter().map(|&d| frag(d)).collect();
            let exact = exact_segments(TagScheme::Two, &stream);
            let need = k_needed(&depths);
            for k in 1..=need.max(1) + 1 {
                let (segs, errors) = KBuffer::run(k, TagScheme::Two, &stream);
                let ok = segs == exact;
                prop_assert_eq!(ok, k >= need, "k={} need={}", k, need);
                prop_assert_eq!(errors == 0, ok, "k={} errors={}", k, errors);
            }
        }
    }

    proptest! {
        /// The paper's insertion-depth k never asks for fewer entries than the exact minimum.
        #[test]
        fn insertion_k_bounds_k_needed(depths in proptest::collection::vec(0u32..50, 0..40)) {
            let depths: Vec<f32> = depths.into_iter().map(|d| d as f32).collect();
            prop_assert!(insertion_k(&depths) >= k_needed(&depths));
        }
    }

    #[test]
    fn insertion_k_counts_the_fragments_passed() {
        // 0 1 2 3 then 0.5 passes three fragments (1, 2, 3): k = 4, which is also the exact
        // minimum (0.5 has rank 1 and arrives three places late).
        assert_eq!(insertion_k(&[0.0, 1.0, 2.0, 3.0, 0.5]), 4);
        assert_eq!(k_needed(&[0.0, 1.0, 2.0, 3.0, 0.5]), 4);
        // Where they differ: 2 3 1 0. The 0 passes all three (k = 4), but a k-buffer of 3
        // entries already holds 2 3 1 when 0 arrives, pops 0 and then 1: exact with k = 3.
        assert_eq!(insertion_k(&[2.0, 3.0, 1.0, 0.0]), 4);
        assert_eq!(k_needed(&[2.0, 3.0, 1.0, 0.0]), 3);
        assert_eq!(insertion_k(&[5.0]), 1);
        assert_eq!(insertion_k(&[]), 1);
        assert_eq!(insertion_k(&[1.0, 1.0, 1.0]), 1);
    }

    #[test]
    fn one_fragment_k_places_late_is_reported() {
        // Rank 1 arrives k places late: k entries are not enough, k + 1 are.
        for k in 1..8usize {
            let mut depths: Vec<f32> = (0..20).map(|i| i as f32).collect();
            let late = depths.remove(1);
            depths.insert(1 + k, late);
            assert_eq!(k_needed(&depths), k + 1);
            let stream: Vec<Fragment> = depths.iter().map(|&d| frag(d)).collect();
            let (_, errors) = KBuffer::run(k, TagScheme::Two, &stream);
            assert!(errors > 0);
            let (segs, errors) = KBuffer::run(k + 1, TagScheme::Two, &stream);
            assert_eq!(errors, 0);
            assert_eq!(segs, exact_segments(TagScheme::Two, &stream));
        }
    }

    #[test]
    fn tag_schemes_differ_only_on_boundary_pairs() {
        use Tag::*;
        // A thin part: the ray enters and leaves through the boundary faces of one tet.
        assert!(TagScheme::Two.composites(Entry, Exit));
        assert!(!TagScheme::Single.composites(Entry, Exit));
        // Leaving and re-entering: a gap for both.
        assert!(!TagScheme::Two.composites(Exit, Entry));
        assert!(!TagScheme::Single.composites(Exit, Entry));
        for (a, b) in [(Interior, Exit), (Entry, Interior), (Interior, Interior)] {
            assert!(TagScheme::Two.composites(a, b) && TagScheme::Single.composites(a, b));
        }
    }
}
