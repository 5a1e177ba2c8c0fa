//! What HAVS's `prepare` uploads and builds, stage by stage: the tagged mesh in chunked
//! storage, the face centroids of the CPU sort, the 3D pre-integrated table, the order buffer
//! and its per-chunk uniforms, the draw and drain pipelines, and the GPU sort's key pass.

use rayon::prelude::*;
use render_core::bind::{chunked_wgsl, range_entries, whole};
use render_core::gpu::{LayoutEntries, Lifetime, MemoryLedger};
use render_core::preintegration::Table3d;
use render_core::table_texture::TableTexture;
use render_core::{ChunkedBuffer, Gpu, Optics};

use crate::abuffer::Geometry;
use crate::{
    mesh_decls, shader_source, GpuSortState, HavsSettings, KeyUniforms, Mode, Uniforms,
    KEY_MESH_BINDING, MESH_BINDING,
};

/// The vertex and face arrays, split over as many storage bindings as they need (the shaders
/// read them through the generated `verts_at` / `faces_at`).
pub(crate) fn upload_mesh(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    geometry: &Geometry,
    max_binding: u64,
) -> anyhow::Result<(ChunkedBuffer, ChunkedBuffer)> {
    let mut upload = |label: &str, data: &[u8], elem_bytes: u64| {
        ChunkedBuffer::with_data(
            gpu,
            ledger,
            label,
            Lifetime::Persistent,
            data,
            elem_bytes,
            max_binding,
            wgpu::BufferUsages::STORAGE,
        )
    };
    let verts = upload("havs vertices", bytemuck::cast_slice(&geometry.verts), 16)?;
    let faces = upload("havs faces", bytemuck::cast_slice(&geometry.faces), 4)?;
    Ok((verts, faces))
}

/// The faces' centroids, what the CPU sort keys on (12 B a face); the GPU sort's key pass
/// computes them from the uploaded faces.
pub(crate) fn face_centroids(geometry: &Geometry) -> Vec<[f32; 3]> {
    geometry
        .faces
        .par_iter()
        .map(|f| {
            let p = f.map(|v| geometry.verts[v as usize]);
            [0, 1, 2].map(|a| (p[0][a] + p[1][a] + p[2][a]) / 3.0)
        })
        .collect()
}

/// The 3D pre-integrated table (s_front, s_back, length) of `settings`' size, lengths up to
/// `max_len` (the longest edge: no segment inside a tet is longer).
pub(crate) fn table(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    optics: &Optics,
    s: HavsSettings,
    max_len: f64,
) -> anyhow::Result<TableTexture> {
    let (n_s, n_l) = (s.table_scalar, s.table_length);
    let table = Table3d::build(optics, n_s as usize, n_l as usize, max_len);
    TableTexture::new(
        gpu,
        ledger,
        "havs preintegration table",
        [n_s, n_s, n_l],
        &table.data,
    )
}

/// The order buffer (face indices front to back), bound in chunks that each fit one storage
/// binding, each chunk with its uniforms; and the frame's counters.
pub(crate) struct OrderBuffers {
    pub order: wgpu::Buffer,
    pub chunks: Vec<std::ops::Range<u64>>,
    pub uniforms: Vec<wgpu::Buffer>,
    pub counters: wgpu::Buffer,
}

impl OrderBuffers {
    pub(crate) fn new(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        num_faces: u64,
        max_binding: u64,
    ) -> anyhow::Result<OrderBuffers> {
        let storage = wgpu::BufferUsages::STORAGE;
        // Chunk offsets aligned as the device requires.
        let align_elems = (gpu.limits.min_storage_buffer_offset_alignment as u64 / 4).max(1);
        let per_chunk = ((max_binding / 4) / align_elems * align_elems).max(align_elems);
        let chunks: Vec<_> = (0..num_faces.div_ceil(per_chunk))
            .map(|i| i * per_chunk..((i + 1) * per_chunk).min(num_faces))
            .collect();
        let order = ledger.buffer(
            gpu,
            "havs face order",
            Lifetime::PerFrame,
            num_faces * 4,
            storage | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        )?;
        let uniforms: Vec<wgpu::Buffer> = chunks
            .iter()
            .map(|_| {
                ledger.buffer(
                    gpu,
                    "havs uniforms",
                    Lifetime::PerFrame,
                    std::mem::size_of::<Uniforms>() as u64,
                    wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                )
            })
            .collect::<anyhow::Result<_>>()?;
        let counters = ledger.buffer(
            gpu,
            "havs counters",
            Lifetime::PerFrame,
            32,
            storage | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        )?;
        Ok(OrderBuffers {
            order,
            chunks,
            uniforms,
            counters,
        })
    }
}

/// The draw/drain bind-group layout and the pipelines over it.
pub(crate) struct Pipelines {
    pub layout: wgpu::BindGroupLayout,
    pub draw: wgpu::RenderPipeline,
    /// `mode=fragment-race`: the draw with the row's per-pixel counts (`fs_kbuffer_counting`).
    pub counting: Option<wgpu::RenderPipeline>,
    pub drain: wgpu::ComputePipeline,
}

impl Pipelines {
    pub(crate) fn new(
        gpu: &Gpu,
        s: HavsSettings,
        verts: &ChunkedBuffer,
        faces: &ChunkedBuffer,
        filterable: bool,
    ) -> Pipelines {
        let all =
            wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let fc = wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let layout = LayoutEntries::new(all)
            .uniform(0)
            .read(3)
            .with(TableTexture::layout_entries(filterable, 4, 5, fc))
            .visible(fc)
            .read_write(6..=10)
            .with(verts.layout_entries(MESH_BINDING, all, true))
            .with(faces.layout_entries(MESH_BINDING + verts.bindings(), all, true))
            .build(gpu, "havs layout");
        let pipeline_layout = gpu.pipeline_layout("havs pipeline layout", &[&layout]);
        let module = gpu.shader(
            "havs",
            &shader_source(s.k, &mesh_decls(verts, faces, MESH_BINDING)),
        );
        // Every face is needed from both sides (entry and exit of a ray). wgpu needs an
        // attachment; the k-buffer lives in storage, so nothing is written to it.
        let draw = |label: &str, entry: &str| {
            gpu.triangle_pipeline(
                label,
                &pipeline_layout,
                &module,
                "vs",
                entry,
                wgpu::TextureFormat::R8Unorm,
                None,
                wgpu::ColorWrites::empty(),
            )
        };
        let (fs_entry, drain_entry) = match s.mode {
            Mode::FragmentRace => ("fs_kbuffer", "drain"),
            Mode::RaceFree => ("fs_append", "resolve_lists"),
        };
        Pipelines {
            draw: draw("havs draw", fs_entry),
            counting: (s.mode == Mode::FragmentRace)
                .then(|| draw("havs draw, counting", "fs_kbuffer_counting")),
            drain: gpu.compute_pipeline("havs drain", Some(&pipeline_layout), &module, drain_entry),
            layout,
        }
    }
}

impl GpuSortState {
    pub(crate) fn new(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        verts: &ChunkedBuffer,
        faces: &ChunkedBuffer,
        num_faces: u64,
    ) -> anyhow::Result<GpuSortState> {
        // Keys and ids larger than one storage binding are written and sorted as chunks of
        // one buffer each (render_core::bind::range_entries; the sort does the same).
        let per_chunk = gpu.max_storage_binding() / 4;
        let chunks = num_faces.max(1).div_ceil(per_chunk) as u32;
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let mut per_frame = |label: &str, bytes: u64, usage: wgpu::BufferUsages| {
            ledger.buffer(gpu, label, Lifetime::PerFrame, bytes, usage)
        };
        let keys = per_frame("havs sort keys", num_faces * 4, usage)?;
        let ids = per_frame("havs sort ids", num_faces * 4, usage)?;
        let key_uniforms = per_frame(
            "havs key uniforms",
            std::mem::size_of::<KeyUniforms>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let keys_binding = KEY_MESH_BINDING + verts.bindings() + faces.bindings();
        let ids_binding = keys_binding + chunks;
        let source = mesh_decls(verts, faces, KEY_MESH_BINDING)
            + &chunked_wgsl("keys", "f32", 0, keys_binding, chunks, per_chunk, false)
            + &chunked_wgsl("ids", "u32", 0, ids_binding, chunks, per_chunk, false)
            + include_str!("keys.wgsl");
        render_core::bind::check_storage_bindings(
            gpu,
            "HAVS face keys",
            verts.bindings() + faces.bindings() + 2 * chunks,
        )?;
        let module = gpu.shader("havs keys", &source);
        let key_pipeline = gpu.compute_pipeline("havs face keys", None, &module, "face_keys");
        let key_bind_group = gpu.bind_group(
            "havs keys",
            &key_pipeline.get_bind_group_layout(0),
            &[
                vec![whole(0, &key_uniforms)],
                verts.bind_entries(KEY_MESH_BINDING),
                faces.bind_entries(KEY_MESH_BINDING + verts.bindings()),
                range_entries(keys_binding, &keys, 4, per_chunk, chunks, num_faces),
                range_entries(ids_binding, &ids, 4, per_chunk, chunks, num_faces),
            ]
            .concat(),
        );
        let sorter = render_core::gpu_sort::GpuRadixSort::new(gpu, num_faces as u32, ledger)?;
        Ok(GpuSortState {
            sorter,
            keys,
            ids,
            key_uniforms,
            key_pipeline,
            key_bind_group,
        })
    }
}
