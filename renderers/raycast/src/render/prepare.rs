//! What `prepare` uploads and builds, by concern: the mesh's textures (§3.1), the boundary
//! faces phases 1–2 rasterise, the pre-integration table (§2.2), and the frame's parameter
//! block with the bind groups that hold it.

use datasets::TetMesh;
use render_core::bind;
use render_core::gpu::{Lifetime, MemoryLedger};
use render_core::preintegration::{Table2d, Table3d};
use render_core::table_texture::TableTexture;
use render_core::texel_texture::TexelTexture;
use render_core::{FrameTimer, Gpu, Optics};

use super::{Raycast, State};
use crate::layout::{MeshLayout, MESH_TEXTURE_BYTES, MESH_TEXTURE_WIDTH};
use crate::resources::{FrameParams, Pipelines};
use crate::settings::{Mode, TableKind};
use crate::{TABLE_LENGTH, TABLE_SCALAR};

impl State {
    /// Packs and uploads `mesh` for `r`'s settings, and builds the pipelines.
    pub(super) fn new(
        gpu: &Gpu,
        r: &Raycast,
        mesh: &TetMesh,
        optics: &Optics,
    ) -> anyhow::Result<State> {
        let max_binding = layer_bytes(gpu, r.max_binding);
        let mut layout = MeshLayout::build(mesh, optics, max_binding)?;
        let slots = layout.chunks.len();
        check_limits(gpu, slots)?;
        let mut ledger = MemoryLedger::default();
        let max_texture_bytes = r.max_texture_bytes.unwrap_or(MESH_TEXTURE_BYTES);
        let mesh_textures = MeshTextures::upload(gpu, &mut ledger, &mut layout, max_texture_bytes)?;
        let (faces, face_vertices) = boundary_faces(gpu, &mut ledger, mesh, &layout)?;
        let (table, inv_table_length) = table(gpu, &mut ledger, r.settings.table, optics, &layout)?;
        let pipes = Pipelines::new(
            gpu,
            mesh_textures.textures.len(),
            mesh_textures.layers_per_texture,
            r.settings.mode == Mode::Passes && !r.compute_passes,
        );
        let frame = FrameBinds::new(gpu, &mut ledger, &pipes, &mesh_textures)?;
        let tets = mesh.num_tets() as u64;
        Ok(State {
            origin: layout.origin,
            mesh_bindings: slots,
            mesh_bytes: mesh_textures.bytes,
            mesh_padding_bytes: mesh_textures.padding_bytes,
            max_binding,
            tets,
            ledger,
            pipes,
            frame_params: frame.params,
            mesh_bind: frame.mesh,
            peel_frame_bind: frame.peel,
            faces,
            face_vertices,
            table,
            inv_table_length,
            length_unit: optics.length_unit,
            // A guard against rays that cycle between tets through round-off: far more steps
            // than a straight ray crosses in any mesh we know (counted as stalled when reached).
            max_steps: (64.0 * (tets as f64).cbrt()).ceil() as u32 + 1024,
            target: None,
            target_bytes: 0,
            timer: FrameTimer::new(gpu),
            last: None,
        })
    }
}

/// The bytes of a mesh texture layer: at most a storage binding's size (so its count and bytes
/// are those of the storage layout it replaced, or `requested`, smaller, from tests) and at
/// most the texture's largest rows.
fn layer_bytes(gpu: &Gpu, requested: Option<u64>) -> u64 {
    let texture_bytes = MESH_TEXTURE_WIDTH as u64 * gpu.limits.max_texture_dimension_2d as u64 * 16;
    let binding = gpu.max_storage_binding();
    requested
        .map_or(binding, |b| b.min(binding))
        .min(texture_bytes)
}

/// Fails, naming the adapter, where it has fewer texture layers than the mesh's `slots` or
/// fewer storage bindings than the traversal.
fn check_limits(gpu: &Gpu, slots: usize) -> anyhow::Result<()> {
    anyhow::ensure!(
        slots as u32 <= gpu.limits.max_texture_array_layers,
        "raycast on {}: the mesh needs {slots} texture layers, the adapter allows {}",
        gpu.adapter.name,
        gpu.limits.max_texture_array_layers
    );
    bind::check_storage_bindings(
        gpu,
        &format!("raycast on {}", gpu.adapter.name),
        // Group 0: the frame; group 1: the traversal's eight buffers.
        1 + 8,
    )
}

/// The boundary faces as geometry for phase 1 (a vertex buffer): each vertex's position in
/// object coordinates about the layout's origin and its tet's (binding, index); and the count
/// of vertices.
fn boundary_faces(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    mesh: &TetMesh,
    layout: &MeshLayout,
) -> anyhow::Result<(wgpu::Buffer, u32)> {
    let o = layout.origin;
    let mut verts: Vec<u32> = Vec::with_capacity(mesh.boundary_faces().len() * 15);
    for bf in mesh.boundary_faces() {
        let r = layout.tet_ref(bf.tet);
        for v in bf.vertices(mesh) {
            let p = mesh.points[v as usize];
            for a in 0..3 {
                verts.push(((p[a] as f64 - o[a]) as f32).to_bits());
            }
            verts.push(r.chunk);
            verts.push(r.local);
        }
    }
    let buffer = ledger.buffer_init(
        gpu,
        "raycast boundary faces",
        Lifetime::Persistent,
        bytemuck::cast_slice(&verts),
        wgpu::BufferUsages::VERTEX,
    )?;
    Ok((buffer, (verts.len() / 5) as u32))
}

/// The pre-integration table of `kind` and 1 / the length its last entry stands for. The table
/// is a filtered 3D texture, one sample a step as the paper's fragment program looks it up
/// (§2.2); the 2D table is one layer of it.
fn table(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    kind: TableKind,
    optics: &Optics,
    layout: &MeshLayout,
) -> anyhow::Result<(TableTexture, f32)> {
    let scalar = TABLE_SCALAR as u32;
    let (label, data, size, length) = match kind {
        TableKind::ThreeD => {
            let t = Table3d::build(optics, TABLE_SCALAR, TABLE_LENGTH, layout.longest_edge);
            let size = [scalar, scalar, TABLE_LENGTH as u32];
            ("raycast 3D table", t.data, size, layout.longest_edge)
        }
        TableKind::TwoD => {
            let t = Table2d::build(optics, TABLE_SCALAR, layout.mean_edge);
            (
                "raycast 2D table",
                t.data,
                [scalar, scalar, 1],
                layout.mean_edge,
            )
        }
    };
    let texture = TableTexture::new(gpu, ledger, label, size, &data)?;
    Ok((texture, (1.0 / length.max(f64::MIN_POSITIVE)) as f32))
}

/// The frame's parameter block, bound in group 0 with the mesh's textures and, for the peel and
/// the tile passes, as a uniform block of its own.
struct FrameBinds {
    params: wgpu::Buffer,
    mesh: wgpu::BindGroup,
    peel: wgpu::BindGroup,
}

impl FrameBinds {
    fn new(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        pipes: &Pipelines,
        mesh_textures: &MeshTextures,
    ) -> anyhow::Result<FrameBinds> {
        let params = ledger.buffer(
            gpu,
            "raycast frame params",
            Lifetime::PerFrame,
            std::mem::size_of::<FrameParams>() as u64,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::UNIFORM
                | wgpu::BufferUsages::COPY_DST,
        )?;
        let mut entries = vec![bind::whole(0, &params)];
        let views = mesh_textures.textures.iter().map(|t| &t.view);
        entries.extend((1..).zip(views).map(|(b, v)| bind::view_entry(b, v)));
        let mesh = gpu.bind_group("raycast frame + mesh", &pipes.layouts.mesh, &entries);
        // Set once per peeling layer (a render pass), never per dispatch: lavapipe keeps memory
        // for every dispatch that sets a group holding a uniform buffer (docs/profile.md).
        let peel = gpu.bind_group(
            "raycast peel frame",
            &pipes.layouts.peel_frame,
            &[bind::whole(0, &params)],
        );
        Ok(FrameBinds { params, mesh, peel })
    }
}

/// Label of the texture that holds the mesh.
const MESH_TEXTURE_LABEL: &str = "raycast mesh texture";

/// The mesh in textures of at most `max_texture_bytes` ([`MESH_TEXTURE_BYTES`]), whole layers
/// each, every layer as many rows as the largest needs.
struct MeshTextures {
    textures: Vec<TexelTexture>,
    layers_per_texture: u32,
    /// The texels written (§3.1's 144 B/tet is a claim about the layout).
    bytes: u64,
    /// The padding of each layer's last row, read from the ledger's allocation.
    padding_bytes: u64,
}

impl MeshTextures {
    /// Uploads `layout`'s layers and drops their host texels: the GPU's copy is the only one
    /// kept (`layout` keeps its addressing and origin).
    fn upload(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        layout: &mut MeshLayout,
        max_texture_bytes: u64,
    ) -> anyhow::Result<MeshTextures> {
        let layers = layout.chunks.len();
        let rows = layout.texture_rows();
        let layer_bytes = rows as u64 * MESH_TEXTURE_WIDTH as u64 * 16;
        let per_texture = (max_texture_bytes / layer_bytes).clamp(1, layers as u64) as usize;
        let textures = (0..layers.div_ceil(per_texture))
            .map(|k| {
                let layers = (layers - k * per_texture).min(per_texture);
                TexelTexture::new(
                    gpu,
                    ledger,
                    MESH_TEXTURE_LABEL,
                    Lifetime::Persistent,
                    rows,
                    layers as u32,
                )
            })
            .collect::<anyhow::Result<Vec<_>>>()?;
        let mut bytes = 0;
        for (c, data) in std::mem::take(&mut layout.chunks).into_iter().enumerate() {
            let layer = (c % per_texture) as u32;
            bytes += textures[c / per_texture].write_layer(gpu, layer, &data);
        }
        Ok(MeshTextures {
            textures,
            layers_per_texture: per_texture as u32,
            bytes,
            padding_bytes: ledger.bytes_labelled(MESH_TEXTURE_LABEL) - bytes,
        })
    }
}
