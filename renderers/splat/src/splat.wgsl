// Splatting (Grau & Tost §3.6) as a compute pass: one invocation per voxel of one bucket.
// The paper draws point sprites; on a software rasteriser a quad's triangle setup costs more
// than its few fragments. A voxel of bucket b belongs to the sheets of slabs b - r ... b + r
// (each slab splats buckets i - r ... i + r), so its invocation projects it once and adds to
// all 2r + 1 of them, held as a ring of sheets (slot = slab mod (2r + 1)); slab b - r is then
// complete and the host composites it before bucket b + 1, which reuses its slot. The sums
// are those of splatting each slab on its own, term for term: only the voxel's projection
// and its pixel walk are shared. Each invocation walks the pixel centres of its footprint
// square — the rasteriser's rule for an axis-aligned quad: a centre on the left/top edge is
// in, on the right/bottom edge out (coverage.rs is the CPU twin) — looks up the footprint
// slice of its offset from each slab (one table of all slices, kernel.rs) and adds
// (value * footprint, footprint) in fixed point, so the sums are exact and independent of
// the invocations' order.

// Sheet sums are stored as round(x * SHEET_ONE) in u32 (composite.wgsl divides back): a
// footprint's sum over the voxels of one slab is about 1 (the kernels on the lattice sum to
// 1, kernel.rs), far below the 2^32 / 2^24 = 256 that would wrap, and each term is rounded to
// 6e-8.
const SHEET_ONE: f32 = 16777216.0;

@group(0) @binding(0) var<storage, read> fr: Frame;
// The invocation's copy of the frame block, read once at its start: with `fr` read in the
// pixel loop, among the atomics on `sheet`, Teapot and Engine (CPU buckets, 256²) took
// 10-20 % longer a frame (docs/profile.md, "Uniform buffers on lavapipe").
var<private> frame: Frame;
@group(0) @binding(1) var<storage, read> sorted_in: array<vec4<f32>>;
// The footprint slices (FootprintTable::bordered) as a 3D texture, texel (x, y) of slice row
// q. With TABLE_FILTERED (prepended by gpu.rs: the device filters R32Float) one trilinear
// sample a slab does the two slices' bilinear lookups and their mix, as the paper looks its
// footprints up in a texture (§3.6); the eight storage loads interpolated by hand before were
// half of this pass on a CPU backend, which runs a storage load lane by lane
// (docs/roofline.md). Without filtering, the same eight texels are loaded and interpolated by
// hand (`bilinear`), the arithmetic of FootprintTable::sample.
@group(0) @binding(2) var table: texture_3d<f32>;
@group(0) @binding(6) var table_sampler: sampler;
@group(0) @binding(3) var image_tex: texture_2d<f32>;
// Splat fragments early splat elimination dropped (the row's `ese_dropped_fragments`).
@group(0) @binding(4) var<storage, read_write> ese_dropped: atomic<u32>;
// Per pixel and ring slot (sum value * w, sum w): pixels row-major, y down, each pixel's
// 2r + 1 slots together (one cache line for r = 2).
@group(0) @binding(5) var<storage, read_write> sheet: array<atomic<u32>>;
@group(1) @binding(0) var<storage, read> slab: Slab;

// Where a voxel's footprint is looked up this slab: the first of the two slice rows its
// offset from the slab falls between (kernel.rs, FootprintTable::bordered) and the weight of
// the second.
struct Slices {
    q0: i32,
    fq: f32,
}

fn slices_of(delta: f32) -> Slices {
    let rows = (2u * frame.radius_slabs + 1u) * frame.subslices + 1u;
    let qf = clamp((delta + f32(frame.radius_slabs)) * f32(frame.subslices), 0.0, f32(rows - 1u));
    let q0 = min(u32(floor(qf)), rows - 2u);
    return Slices(i32(q0), qf - f32(q0));
}

fn texel(xy: vec2<i32>, q: i32) -> f32 {
    return textureLoad(table, vec3<i32>(xy, q), 0).x;
}

fn bilinear(xy: vec2<i32>, q: i32, fx: f32, fy: f32) -> f32 {
    return mix(
        mix(texel(xy, q), texel(xy + vec2<i32>(1, 0), q), fx),
        mix(texel(xy + vec2<i32>(0, 1), q), texel(xy + vec2<i32>(1, 1), q), fx),
        fy
    );
}

// Where a pixel falls in a footprint slice: the bordered texel of its bilinear cell's first
// corner, and the fractions. Twin of FootprintTable::sample (kernel.rs): bilinear
// in a slice, 0 outside the table (the slices' zero border; u, v are clamped onto it).
struct Cell {
    at: vec2<i32>,
    fx: f32,
    fy: f32,
}

fn cell_of(kxy: vec2<f32>) -> Cell {
    let f = f32(frame.footprint);
    let u = clamp((kxy.x + frame.kernel_radius) / (2.0 * frame.kernel_radius) * f - 0.5, -1.0, f - 0.5);
    let v = clamp((kxy.y + frame.kernel_radius) / (2.0 * frame.kernel_radius) * f - 0.5, -1.0, f - 0.5);
    let x0 = floor(u);
    let y0 = floor(v);
    return Cell(vec2<i32>(i32(x0 + 1.0), i32(y0 + 1.0)), u - x0, v - y0);
}

// The footprint of one slab: linear between its two slice rows.
fn footprint(sl: Slices, c: Cell) -> f32 {
    if TABLE_FILTERED {
        // Texel centres at +0.5: the cell's first corner plus the fractions, on every axis.
        let size = vec3<f32>(textureDimensions(table));
        let at = vec3<f32>(vec2<f32>(c.at) + vec2<f32>(c.fx, c.fy), f32(sl.q0) + sl.fq) + 0.5;
        return textureSampleLevel(table, table_sampler, at / size, 0.0).x;
    }
    return mix(bilinear(c.at, sl.q0, c.fx, c.fy), bilinear(c.at, sl.q0 + 1, c.fx, c.fy), sl.fq);
}

// First pixel index whose centre k + 1/2 is >= edge, clamped to [0, n].
fn first_centre(edge: f32, n: f32) -> u32 {
    return u32(clamp(ceil(edge - 0.5), 0.0, n));
}

// A voxel's footprint is split by rows over `slab.lanes` invocations (the host sizes it from
// the largest footprint of the frame, `Splat::lanes`): one invocation per voxel walked up to
// thousands of pixels one after the other, and a bucket holds too few voxels to fill a GPU
// (docs/gpu.md). The sums are fixed point, so the split changes no bit of the image.
// SPLAT_WORKGROUP (gpu.rs, prepended to this source) invocations a workgroup.
@compute @workgroup_size(SPLAT_WORKGROUP)
fn splat_cs(@builtin(global_invocation_id) g: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let lanes = max(slab.lanes, 1u);
    let flat = g.x + g.y * nwg.x * SPLAT_WORKGROUP;
    let i = flat / lanes;
    let lane = flat % lanes;
    if (i >= slab.count) {
        return;
    }
    frame = fr;
    let v = sorted_in[slab.first + i];
    let d = view_depth(frame, v.xyz);
    let clip = frame.view_proj * vec4<f32>(v.xyz, 1.0);
    if (clip.w <= 0.0 || d <= 0.0) {
        return;
    }
    let ndc = clip.xy / clip.w;
    var ppw = frame.focal_px;
    if (frame.perspective != 0u) {
        ppw = frame.focal_px / d;
    }
    let half_px = frame.kernel_radius_world * ppw;
    let centre = vec2<f32>((ndc.x + 1.0) * 0.5 * frame.viewport.x, (1.0 - ndc.y) * 0.5 * frame.viewport.y);
    let x0 = first_centre(centre.x - half_px, frame.viewport.x);
    let x1 = first_centre(centre.x + half_px, frame.viewport.x);
    let y0 = first_centre(centre.y - half_px, frame.viewport.y);
    let y1 = first_centre(centre.y + half_px, frame.viewport.y);
    // Kernel units per pixel: the quad's corners are +-kernel_radius.
    let k_per_px = frame.kernel_radius / half_px;
    // The slabs this step adds to, and the first one's ring slot.
    let ring = 2u * frame.radius_slabs + 1u;
    let s0 = slab.first_slab;
    let s1 = slab.last_slab;
    let slot0 = s0 % ring;
    let in_slabs = (d - frame.d0) * frame.inv_delta;
    let value = clamp(v.w, 0.0, 1.0);
    let width = u32(frame.viewport.x);
    var dropped = 0u;
    for (var y = y0 + lane; y < y1; y += lanes) {
        for (var x = x0; x < x1; x++) {
            // Early splat elimination: nothing behind an opaque pixel can show. The image
            // holds the slabs before s0, so this drops no more than testing each slab would.
            if (frame.ese_alpha <= 1.0) {
                let a = textureLoad(image_tex, vec2<i32>(i32(x), i32(y)), 0).a;
                if (a >= frame.ese_alpha) {
                    dropped += s1 + 1u - s0;
                    continue;
                }
            }
            let kxy = (vec2<f32>(f32(x) + 0.5, f32(y) + 0.5) - centre) * k_per_px;
            let c = cell_of(kxy);
            let pixel = (y * width + x) * ring;
            var slot = slot0;
            for (var s = s0; s <= s1; s++) {
                let w = max(footprint(slices_of(in_slabs - f32(s)), c), 0.0) * frame.density_scale;
                let p = 2u * (pixel + slot);
                // A term that rounds to 0 adds nothing: skip its atomic.
                let wv = u32(w * value * SHEET_ONE + 0.5);
                let ww = u32(w * SHEET_ONE + 0.5);
                if (wv != 0u) {
                    atomicAdd(&sheet[p], wv);
                }
                if (ww != 0u) {
                    atomicAdd(&sheet[p + 1u], ww);
                }
                slot = select(slot + 1u, 0u, slot + 1u == ring);
            }
        }
    }
    if (dropped != 0u) {
        atomicAdd(&ese_dropped, dropped);
    }
}
