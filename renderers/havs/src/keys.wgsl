// GPU sort variant of HAVS' object-space pass: one key per face, the distance from the eye to
// the face's centroid (§5.1), or the distance along the viewing direction for orthographic
// views. The keys and the face indices are then sorted by render_core's GPU radix sort.

struct KeyUniforms {
    // xyz: eye; w: 1 for perspective.
    eye: vec4<f32>,
    forward: vec4<f32>,
    faces: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> ku: KeyUniforms;
// verts_at / faces_at: declared by the Rust (render_core::ChunkedBuffer) at bindings 5..;
// keys_set / ids_set after them, each array split over as many storage bindings as the
// faces need (render_core::bind::chunked_wgsl), as the GPU radix sort reads them.

@compute @workgroup_size(256)
fn face_keys(@builtin(global_invocation_id) g: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    let f = g.x + g.y * nw.x * 256u;
    if f >= ku.faces {
        return;
    }
    let c = (verts_at(faces_at(3u * f)).xyz + verts_at(faces_at(3u * f + 1u)).xyz + verts_at(faces_at(3u * f + 2u)).xyz) / 3.0;
    let rel = c - ku.eye.xyz;
    var d = dot(rel, ku.forward.xyz);
    if ku.eye.w > 0.5 {
        d = length(rel);
    }
    keys_set(f, d);
    ids_set(f, f);
}
