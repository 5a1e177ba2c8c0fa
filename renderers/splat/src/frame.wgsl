// Per-frame (and per-brick: n, padded) parameters shared by every splat shader; prepended to
// each shader file. Must match `FrameParams` in gpu.rs.
struct Frame {
    view_proj: mat4x4<f32>,
    // Row 2 of the view matrix: view depth d = -(row . (p, 1)).
    depth_row: vec4<f32>,
    viewport: vec2<f32>,
    // tan of half the field of view, x and y (perspective).
    tan_half: vec2<f32>,
    // Pixels per world unit: orthographic as is, perspective divided by the depth.
    focal_px: f32,
    perspective: u32,
    d0: f32,
    inv_delta: f32,
    delta_world: f32,
    num_slabs: u32,
    n: u32,
    padded: u32,
    radius_slabs: u32,
    subslices: u32,
    footprint: u32,
    tf_entries: u32,
    kernel_radius: f32,
    kernel_unit: f32,
    density_scale: f32,
    ese_alpha: f32,
    kernel_radius_world: f32,
    length_unit: f32,
    pad0: f32,
    pad1: f32,
}

fn view_depth(fr: Frame, p: vec3<f32>) -> f32 {
    let r = fr.depth_row;
    return -(r.x * p.x + r.y * p.y + r.z * p.z + r.w);
}

// One step of a brick (splat.wgsl, composite.wgsl; must match `SlabParams` in gpu.rs): add
// voxels sorted_in[first .. first + count] to the sheets of slabs first_slab ... last_slab,
// then composite ring slot `slot`. A step is one bucket and the slabs it belongs to; the test
// hook `Splat::slab_by_slab` makes it the paper's slab i (buckets i - r ... i + r into slab i
// alone), the twin the ring must equal.
struct Slab {
    first: u32,
    count: u32,
    first_slab: u32,
    last_slab: u32,
    slot: u32,
    // Invocations per voxel (splat.wgsl): invocation j of a voxel takes rows j, j + lanes, ...
    // of its footprint.
    lanes: u32,
    pad1: u32,
    pad2: u32,
}
