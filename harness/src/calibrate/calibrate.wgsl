// Micro-benchmarks of `tetbench calibrate` (see mod.rs). Each entry point stresses one
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

// Rasterisation of triangles that cover pixels, as projected cells do: one right triangle with
// legs of `leg` pixels (the instance index) in each leg×leg cell of a RASTER_SIZE² target,
// drawn with fill_fs and fill's blend. Its corners sit 0.25 pixel off the pixel grid, so no
// pixel centre lies on an edge and each triangle has exactly leg·(leg+1)/2 fragments (the
// centres (i, j) of its cell with i + j < leg). Two leg lengths give the cost per triangle and
// per fragment (mod.rs, `raster_costs`).
const RASTER_SIZE: u32 = 512u;

@vertex
fn raster_vs(
    @builtin(vertex_index) vi: u32,
    @builtin(instance_index) leg: u32,
) -> @builtin(position) vec4<f32> {
    let t = vi / 3u;
    let k = vi % 3u;
    let per_row = RASTER_SIZE / leg;
    let cell = t % (per_row * per_row);
    let corner = vec2<f32>(f32(cell % per_row), f32(cell / per_row)) * f32(leg) + 0.25;
    var o = vec2<f32>(0.0, 0.0);
    if k == 1u {
        o = vec2<f32>(f32(leg), 0.0);
    } else if k == 2u {
        o = vec2<f32>(0.0, f32(leg));
    }
    let p = (corner + o) / f32(RASTER_SIZE) * 2.0 - 1.0;
    return vec4<f32>(p.x, -p.y, 0.5, 1.0);
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

// Ray steps: a walk through a table of 144-byte cells (8 vec4 of geometry + 1 vec4 of
// neighbours, the ray caster's tet record, renderers/raycast layout.rs), each step a dependent
// gather: read the cell's four planes, take the nearest exit among faces the ray leaves
// through (Bernardon et al. 2005 §2.2), read the scalar at the exit, look up one table entry,
// composite, and move to the neighbour across the exit face. WALK_STEPS steps per invocation.
const WALK_STEPS: u32 = 32u;
const WALK_TABLE: u32 = 4096u;

@group(0) @binding(3) var<storage, read> walk_cells: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> walk_next: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read> walk_table: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> walk_out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn walk_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let cells = arrayLength(&walk_next);
    var cell = (id.x * 2654435761u) % cells;
    let o = vec3<f32>(f32(id.x & 15u), f32((id.x >> 4u) & 15u), 0.5) * 0.01;
    let d = normalize(vec3<f32>(0.3, 0.2, 1.0) + o);
    var lambda = 0.0;
    var colour = vec4<f32>(0.0);
    for (var i = 0u; i < WALK_STEPS; i++) {
        let b = cell * 8u;
        var best = 3.0e38;
        var face = 0u;
        for (var f = 0u; f < 4u; f++) {
            let p = walk_cells[b + f];
            let den = dot(d, p.xyz);
            let l = (p.w - dot(o, p.xyz)) / den;
            if den > 0.0 && l < best {
                best = l;
                face = f;
            }
        }
        let g = walk_cells[b + 4u];
        let s = clamp(dot(g.xyz, o + best * d) + g.w, 0.0, 1.0);
        let e = walk_table[u32(s * f32(WALK_TABLE - 1u))];
        colour += (1.0 - colour.a) * e * (best - lambda + walk_cells[b + 5u + (i % 3u)].x);
        lambda = best;
        cell = walk_next[cell][face];
    }
    walk_out[id.x] = colour;
}

// The same walk with the cells in an Rgba32Uint texture (9 texels a cell: the 8 of geometry
// as f32 bits, then the neighbours; render_core::texel_texture) and the table a filtered 3D texture
// sampled once a step: the ray caster's layout since it holds its mesh and its table in
// textures (renderers/raycast, Bernardon et al. 2005 §3.1). work.rs keeps the faster walk.
@group(0) @binding(14) var walk_cells_tex: texture_2d_array<u32>;
@group(0) @binding(15) var walk_table_tex: texture_3d<f32>;
@group(0) @binding(16) var walk_sampler: sampler;

// render_core::texel_texture's `texel_at` (its TEXEL_WGSL is appended by mod.rs).
fn walk_texel(i: u32) -> vec4<u32> {
    return texel_at(walk_cells_tex, 0u, i);
}

@compute @workgroup_size(64)
fn walk_tex_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let dims = textureDimensions(walk_cells_tex);
    let cells = dims.x * dims.y / 9u;
    var cell = (id.x * 2654435761u) % cells;
    let o = vec3<f32>(f32(id.x & 15u), f32((id.x >> 4u) & 15u), 0.5) * 0.01;
    let d = normalize(vec3<f32>(0.3, 0.2, 1.0) + o);
    var lambda = 0.0;
    var colour = vec4<f32>(0.0);
    for (var i = 0u; i < WALK_STEPS; i++) {
        let b = cell * 9u;
        var best = 3.0e38;
        var face = 0u;
        for (var f = 0u; f < 4u; f++) {
            let p = bitcast<vec4<f32>>(walk_texel(b + f));
            let den = dot(d, p.xyz);
            let l = (p.w - dot(o, p.xyz)) / den;
            if den > 0.0 && l < best {
                best = l;
                face = f;
            }
        }
        let g = bitcast<vec4<f32>>(walk_texel(b + 4u));
        let s = clamp(dot(g.xyz, o + best * d) + g.w, 0.0, 1.0);
        let e = textureSampleLevel(walk_table_tex, walk_sampler, vec3<f32>(s, 1.0 - s, fract(best)), 0.0);
        let filler = bitcast<vec4<f32>>(walk_texel(b + 5u + (i % 3u)));
        colour += (1.0 - colour.a) * e * (best - lambda + filler.x);
        lambda = best;
        cell = walk_texel(b + 8u)[face];
    }
    walk_out[id.x] = colour;
}

// Splat fill: what the splatter's compute pass does per voxel (Grau & Tost 2007 §3.6, our
// splat.wgsl): walk the pixel centres of a square of `splat_params.px` pixels; per centre and
// per slab of the voxel's SPLAT_RING (2r + 1 for the default r = 2), a bilinear lookup in two
// footprint slices of a storage table, added to that slab's two-u32 fixed-point sums with
// atomics, a term that rounds to 0 skipping its atomic as the splatter's does. A splat
// fragment is one (voxel, slab, pixel), as the row's `splat_fragments` counts them. Squares
// half a square apart, so each pixel is hit several times, as overlapping splats are. work.rs
// runs it at several square sizes (the per-voxel set-up is spread over more fragments in a
// larger square) and with two tables: one without zeros, and one shaped like the splatter's
// kernel (each slice the section of a ball, zero outside it, so the terms outside the ball
// skip their atomics as the splatter's do); the calibration keeps the fastest.
const SPLAT_RING: u32 = 5u;
const SPLAT_TARGET: u32 = 512u;
const SPLAT_SLICE: u32 = 32u;
const SPLAT_SLICES: u32 = 8u;
const SPLAT_ONE: f32 = 16777216.0;

// x: square side in pixels (even); y: squares per row of the grid.
struct SplatParams {
    px: u32,
    grid: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(7) var<storage, read> splat_table: array<f32>;
@group(0) @binding(8) var<storage, read_write> splat_sheet: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read> splat_params: SplatParams;

fn splat_texel(q: u32, x: i32, y: i32) -> f32 {
    let n = i32(SPLAT_SLICE);
    if x < 0 || y < 0 || x >= n || y >= n {
        return 0.0;
    }
    return splat_table[q * SPLAT_SLICE * SPLAT_SLICE + u32(y) * SPLAT_SLICE + u32(x)];
}

fn splat_bilinear(q: u32, uv: vec2<f32>) -> f32 {
    let f = floor(uv);
    let t = uv - f;
    let i = vec2<i32>(f);
    return mix(mix(splat_texel(q, i.x, i.y), splat_texel(q, i.x + 1, i.y), t.x),
               mix(splat_texel(q, i.x, i.y + 1), splat_texel(q, i.x + 1, i.y + 1), t.x), t.y);
}

// One invocation's square: its origin, the first and one-past-last pixel centres, its slice.
struct SplatSquare {
    origin: vec2<f32>,
    lo: vec2<u32>,
    hi: vec2<u32>,
    q: u32,
}

fn splat_square(id: u32) -> SplatSquare {
    let px = f32(splat_params.px);
    let grid = splat_params.grid;
    let cell = id % (grid * grid);
    let origin = vec2<f32>(f32(cell % grid), f32(cell / grid)) * (px * 0.5) + 0.25;
    return SplatSquare(origin, vec2<u32>(ceil(origin - 0.5)), vec2<u32>(ceil(origin + px - 0.5)), id % 3u);
}

// Where pixel (x, y) falls in the table's slices (texel units, centres at integers).
fn splat_uv(sq: SplatSquare, x: u32, y: u32) -> vec2<f32> {
    return (vec2<f32>(f32(x) + 0.5, f32(y) + 0.5) - sq.origin) / f32(splat_params.px) * f32(SPLAT_SLICE) - 0.5;
}

// Adds a footprint term to slab o's two fixed-point sums of a pixel (a term that rounds to 0
// skips its atomic).
fn splat_add(x: u32, y: u32, o: u32, w: f32) {
    let p = 2u * ((y * SPLAT_TARGET + x) * SPLAT_RING + o);
    let wv = u32(w * 0.5 * SPLAT_ONE + 0.5);
    let ww = u32(w * SPLAT_ONE + 0.5);
    if wv != 0u {
        atomicAdd(&splat_sheet[p], wv);
    }
    if ww != 0u {
        atomicAdd(&splat_sheet[p + 1u], ww);
    }
}

@compute @workgroup_size(256)
fn splat_cs(@builtin(global_invocation_id) id: vec3<u32>) {
    let sq = splat_square(id.x);
    for (var y = sq.lo.y; y < sq.hi.y; y++) {
        for (var x = sq.lo.x; x < sq.hi.x; x++) {
            let uv = splat_uv(sq, x, y);
            for (var o = 0u; o < SPLAT_RING; o++) {
                splat_add(x, y, o, mix(splat_bilinear(sq.q + o, uv), splat_bilinear(sq.q + o + 1u, uv), 0.5));
            }
        }
    }
}

// The same fill with the footprint table in a filtered R32Float 3D texture (the splatter's
// layout where the device filters it): one trilinear sample a slab does the two slices'
// bilinear lookups and their mix; the slices are bordered by a texel of zeros, so that a centre
// outside the table reads 0 as `splat_texel` does.
@group(0) @binding(17) var splat_table_tex: texture_3d<f32>;
@group(0) @binding(18) var splat_sampler: sampler;

@compute @workgroup_size(256)
fn splat_tex_cs(@builtin(global_invocation_id) id: vec3<u32>) {
    let sq = splat_square(id.x);
    let bordered = f32(SPLAT_SLICE + 2u);
    for (var y = sq.lo.y; y < sq.hi.y; y++) {
        for (var x = sq.lo.x; x < sq.hi.x; x++) {
            let uv = clamp(splat_uv(sq, x, y), vec2<f32>(-1.0), vec2<f32>(f32(SPLAT_SLICE)));
            let st = (uv + 1.5) / bordered;
            for (var o = 0u; o < SPLAT_RING; o++) {
                let z = f32(sq.q + o + 1u) / f32(SPLAT_SLICES);
                splat_add(x, y, o, textureSampleLevel(splat_table_tex, splat_sampler, vec3<f32>(st, z), 0.0).x);
            }
        }
    }
}

// Tet classification: the part of a projected tetrahedron's classification that GATOR's vertex
// program (Wylie et al. 2002 §3, gator.wgsl) and fragment PT's first pass (Marroquim et al.
// 2006 §3.2, pass1.wgsl) both do: gather the tet's four vertex indices and positions, project
// them (a 4×4 matrix and the perspective divide), the three orientation tests of the projected
// vertices, and the intersection of the two diagonals (the thick vertex of a class-2
// projection). One invocation per tet; the result is stored so nothing is optimised away.
@group(0) @binding(10) var<storage, read> classify_tets: array<vec4<u32>>;
@group(0) @binding(11) var<storage, read> classify_points: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read> classify_matrix: mat4x4<f32>;
@group(0) @binding(13) var<storage, read_write> classify_out: array<vec4<f32>>;

fn classify_cross(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

@compute @workgroup_size(64)
fn classify_cs(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&classify_tets) {
        return;
    }
    let t = classify_tets[id.x];
    let c0 = classify_matrix * vec4<f32>(classify_points[t.x].xyz, 1.0);
    let c1 = classify_matrix * vec4<f32>(classify_points[t.y].xyz, 1.0);
    let c2 = classify_matrix * vec4<f32>(classify_points[t.z].xyz, 1.0);
    let c3 = classify_matrix * vec4<f32>(classify_points[t.w].xyz, 1.0);
    let q0 = c0.xy / c0.w;
    let q1 = c1.xy / c1.w;
    let q2 = c2.xy / c2.w;
    let q3 = c3.xy / c3.w;
    let a = classify_cross(q1 - q0, q2 - q0);
    let b = classify_cross(q1 - q0, q3 - q0);
    let c = classify_cross(q3 - q0, q2 - q0);
    let t1 = (a >= 0.0) != (b >= 0.0);
    let t2 = (a >= 0.0) != (c >= 0.0);
    // The diagonals of the quad the tests pick: v0v1 against v2v3 or v0v2 against v1v3.
    var d0 = q1 - q0;
    var e0 = q2;
    var e1 = q3;
    if t2 {
        d0 = q2 - q0;
        e0 = q1;
    }
    let bv = e1 - e0;
    let den = classify_cross(d0, bv);
    var alpha = 0.0;
    if den != 0.0 {
        alpha = clamp(classify_cross(bv, q0 - e0) / den, 0.0, 1.0);
    }
    let thick = q0 + alpha * d0;
    classify_out[id.x] = vec4<f32>(thick, alpha, select(0.0, 1.0, t1));
}
