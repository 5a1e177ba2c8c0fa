//! What `prepare` uploads and builds once per mesh: the model, the view-independent tables, the
//! per-frame buffers pass 1 and the sort write, and the two passes' pipelines.

use anyhow::bail;
use datasets::TetMesh;
use render_core::bind::{check_storage_bindings, view_entry, whole as storage, ChunkedBuffer};
use render_core::gpu::{LayoutEntries, Lifetime, MemoryLedger};
use render_core::{Gpu, Optics};

use crate::classify::packed_table;
use crate::{
    exp_table, FragmentPtSettings, Pass1Params, Pass2Params, Shading, SortMode, State, EXP_ENTRIES,
    MESH_BINDING, PSI_SIDE, RECORD_BYTES, TF_ENTRIES, WORKGROUP,
};

/// The arrays both passes read chunk by chunk: the model (vertices, tets) and pass 1's
/// records, bound from [`MESH_BINDING`] on.
struct MeshArrays {
    vertices: ChunkedBuffer,
    tets: ChunkedBuffer,
    records: ChunkedBuffer,
}

impl MeshArrays {
    /// Storage bindings the model and records take.
    fn bindings(&self) -> u32 {
        self.vertices.bindings() + self.tets.bindings() + self.records.bindings()
    }

    /// The WGSL declarations and accessors of the three arrays.
    fn wgsl(&self, records_read_only: bool) -> String {
        let (vertices, tets) = (&self.vertices, &self.tets);
        vertices.wgsl("vertices", "vec4<f32>", 0, MESH_BINDING, true)
            + &tets.wgsl(
                "tets",
                "vec4<u32>",
                0,
                MESH_BINDING + vertices.bindings(),
                true,
            )
            + &self.records.wgsl(
                "records",
                "TetOut",
                0,
                MESH_BINDING + vertices.bindings() + tets.bindings(),
                records_read_only,
            )
    }

    fn bind_entries(&self) -> Vec<wgpu::BindGroupEntry<'_>> {
        let (vertices, tets) = (&self.vertices, &self.tets);
        [
            vertices.bind_entries(MESH_BINDING),
            tets.bind_entries(MESH_BINDING + vertices.bindings()),
            self.records
                .bind_entries(MESH_BINDING + vertices.bindings() + tets.bindings()),
        ]
        .concat()
    }
}

/// The view-independent tables (small; counted as persistent too).
struct Tables {
    truth: wgpu::Buffer,
    tf: wgpu::TextureView,
    expt: wgpu::TextureView,
    psi: wgpu::TextureView,
}

/// Uploads the mesh and the tables and builds both passes: the state every frame uses.
pub(crate) fn build_state(
    settings: &FragmentPtSettings,
    max_binding: Option<u64>,
    gpu: &Gpu,
    mesh: &std::sync::Arc<TetMesh>,
    optics: &Optics,
) -> anyhow::Result<State> {
    check_device_and_mesh(gpu, mesh)?;
    let n = mesh.num_tets() as u64;
    let max_binding = match max_binding {
        Some(b) => b.min(gpu.max_storage_binding()) & !255,
        None => gpu.max_storage_binding(),
    }
    .max(256);
    let groups = n.div_ceil(WORKGROUP as u64).max(1);
    let gx = groups.min(gpu.limits.max_compute_workgroups_per_dimension as u64);
    let dispatch = (gx as u32, groups.div_ceil(gx) as u32);
    let mut ledger = MemoryLedger::default();
    let storage_use = wgpu::BufferUsages::STORAGE;
    let (vertices, tets) = upload_model(gpu, &mut ledger, mesh, max_binding)?;
    let model_bytes = ledger.persistent;
    let tables = upload_tables(gpu, &mut ledger, optics, settings.shading)?;
    // Per-frame buffers written by pass 1 and the sort.
    let records = ChunkedBuffer::new(
        gpu,
        &mut ledger,
        "fragment-pt pass-1 records",
        Lifetime::PerFrame,
        n,
        RECORD_BYTES,
        max_binding,
        storage_use | wgpu::BufferUsages::COPY_SRC,
    )?;
    let arrays = MeshArrays {
        vertices,
        tets,
        records,
    };
    let mesh_bindings = arrays.bindings();
    check_storage_bindings(gpu, "fragment-pt pass 2", 4 + mesh_bindings)?;
    let depths = ledger.buffer(
        gpu,
        "fragment-pt centroid depths",
        Lifetime::PerFrame,
        n * 4,
        storage_use | wgpu::BufferUsages::COPY_SRC,
    )?;
    let order = ledger.buffer(
        gpu,
        "fragment-pt order",
        Lifetime::PerFrame,
        n * 4,
        storage_use | wgpu::BufferUsages::COPY_DST,
    )?;
    let uniform = wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST;
    let pass1_params = ledger.buffer(
        gpu,
        "fragment-pt pass-1 params",
        Lifetime::PerFrame,
        std::mem::size_of::<Pass1Params>() as u64,
        uniform,
    )?;
    let pass2_params = ledger.buffer(
        gpu,
        "fragment-pt pass-2 params",
        Lifetime::PerFrame,
        std::mem::size_of::<Pass2Params>() as u64,
        uniform,
    )?;
    let (pass1, pass1_bind) = pass1_pipeline(gpu, &arrays, &pass1_params, &tables, &depths, &order);
    let (pass2, pass2_bind) = pass2_pipeline(
        gpu,
        &arrays,
        settings.shading,
        &pass2_params,
        &order,
        &tables,
    );
    let gpu_sort = if settings.sort == SortMode::Gpu {
        Some(render_core::gpu_sort::GpuRadixSort::new(
            gpu,
            n as u32,
            &mut ledger,
        )?)
    } else {
        None
    };
    let visibility = if settings.sort == SortMode::Mpvonc {
        Some(render_core::visibility::VisibilitySorter::new(
            render_core::visibility::VisibilityOrder::Mpvonc,
        ))
    } else {
        None
    };
    let range = optics.scalar_max - optics.scalar_min;
    Ok(State {
        mesh: std::sync::Arc::clone(mesh),
        tets: n as u32,
        ledger,
        model_bytes,
        pass1_params,
        pass2_params,
        records: arrays.records,
        dispatch,
        mesh_bindings,
        depths,
        order,
        pass1,
        pass1_bind,
        pass2,
        pass2_bind,
        target: None,
        queries: timestamp_queries(gpu),
        scalar_min: optics.scalar_min as f32,
        scalar_inv_range: if range > 0.0 {
            (1.0 / range) as f32
        } else {
            0.0
        },
        inv_length_unit: (1.0 / optics.length_unit.max(f64::MIN_POSITIVE)) as f32,
        indices: Vec::new(),
        radix: Default::default(),
        merge: Vec::new(),
        visibility,
        gpu_sort,
        fragments: Default::default(),
    })
}

/// Refuses an adapter that cannot blend into the target and a mesh whose whole-array buffers
/// or vertex indices would not fit.
fn check_device_and_mesh(gpu: &Gpu, mesh: &TetMesh) -> anyhow::Result<()> {
    if !gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
        bail!(
            "fragment-pt: adapter {} cannot blend into Rgba32Float (FLOAT32_BLENDABLE)",
            gpu.adapter.name
        );
    }
    let n = mesh.num_tets() as u64;
    // Vertices, tets and pass-1 records are split over storage bindings; the
    // centroid depths and the order stay one binding each, because the GPU radix sort and
    // the CPU upload take them whole (4 B/tet: 33 M tets at lavapipe's 128 MiB).
    let adapter_binding = gpu.max_storage_binding();
    if n * 4 > adapter_binding {
        bail!(
            "fragment-pt: mesh {} has {n} tets; its depth and order arrays need {} bytes \
             each in one storage binding, the adapter allows {adapter_binding} bytes \
             (max_storage_buffer_binding_size)",
            mesh.name,
            n * 4
        );
    }
    if n > u32::MAX as u64 / 12 {
        bail!("fragment-pt: {n} tets exceed the 32-bit vertex index range (12 per tet)");
    }
    Ok(())
}

/// The model: vertices (xyz + scalar) and tet indices — nothing else persistent per tet.
fn upload_model(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    mesh: &TetMesh,
    max_binding: u64,
) -> anyhow::Result<(ChunkedBuffer, ChunkedBuffer)> {
    let storage_use = wgpu::BufferUsages::STORAGE;
    let verts: Vec<[f32; 4]> = mesh
        .points
        .iter()
        .zip(&mesh.scalars)
        .map(|(p, &s)| [p[0], p[1], p[2], s])
        .collect();
    let tets: Vec<[u32; 4]> = mesh.tets.clone();
    let vertices = ChunkedBuffer::with_data(
        gpu,
        ledger,
        "fragment-pt vertices",
        Lifetime::Persistent,
        bytemuck::cast_slice(&verts),
        16,
        max_binding,
        storage_use,
    )?;
    drop(verts);
    let tet_buf = ChunkedBuffer::with_data(
        gpu,
        ledger,
        "fragment-pt tets",
        Lifetime::Persistent,
        bytemuck::cast_slice(&tets),
        16,
        max_binding,
        storage_use,
    )?;
    drop(tets);
    Ok((vertices, tet_buf))
}

/// The truth table, the transfer function, the exponential table and the ψ table.
fn upload_tables(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    optics: &Optics,
    shading: Shading,
) -> anyhow::Result<Tables> {
    let truth = ledger.buffer_init(
        gpu,
        "fragment-pt truth table",
        Lifetime::Persistent,
        bytemuck::cast_slice(&packed_table()),
        wgpu::BufferUsages::STORAGE,
    )?;
    let tf = render_core::bind::lookup_texture(
        gpu,
        ledger,
        "fragment-pt transfer function",
        wgpu::TextureFormat::Rgba32Float,
        (TF_ENTRIES as u32, 1),
        bytemuck::cast_slice(&optics.tf.rgb_kappa_table(TF_ENTRIES)),
    )?;
    let expt = render_core::bind::lookup_texture(
        gpu,
        ledger,
        "fragment-pt exp table",
        wgpu::TextureFormat::R32Float,
        (EXP_ENTRIES as u32, 1),
        bytemuck::cast_slice(&exp_table()),
    )?;
    let (psi_side, psi_values) = match shading {
        Shading::Psi => (
            PSI_SIDE as u32,
            render_core::preintegration::PsiTable::build(PSI_SIDE).data,
        ),
        // The average mode never reads ψ; bind a minimal texture.
        Shading::Average => (2, vec![0.0; 4]),
    };
    let psi = render_core::bind::lookup_texture(
        gpu,
        ledger,
        "fragment-pt psi table",
        wgpu::TextureFormat::R32Float,
        (psi_side, psi_side),
        bytemuck::cast_slice(&psi_values),
    )?;
    Ok(Tables {
        truth,
        tf,
        expt,
        psi,
    })
}

/// Pass 1, the classification compute pass, and its bind group.
fn pass1_pipeline(
    gpu: &Gpu,
    arrays: &MeshArrays,
    params: &wgpu::Buffer,
    tables: &Tables,
    depths: &wgpu::Buffer,
    order: &wgpu::Buffer,
) -> (wgpu::ComputePipeline, wgpu::BindGroup) {
    let module = gpu.shader(
        "fragment-pt pass 1",
        &(arrays.wgsl(false) + include_str!("pass1.wgsl")),
    );
    let pass1 = gpu.compute_pipeline("fragment-pt pass 1", None, &module, "classify");
    let bind = gpu.bind_group(
        "fragment-pt pass 1",
        &pass1.get_bind_group_layout(0),
        &[
            vec![
                storage(0, params),
                storage(3, &tables.truth),
                storage(5, depths),
                storage(6, order),
            ],
            arrays.bind_entries(),
        ]
        .concat(),
    );
    (pass1, bind)
}

/// Pass 2, the fans drawn back to front, and its bind group.
fn pass2_pipeline(
    gpu: &Gpu,
    arrays: &MeshArrays,
    shading: Shading,
    params: &wgpu::Buffer,
    order: &wgpu::Buffer,
    tables: &Tables,
) -> (wgpu::RenderPipeline, wgpu::BindGroup) {
    let module = gpu.shader(
        "fragment-pt pass 2",
        &(arrays.wgsl(true) + include_str!("pass2.wgsl")),
    );
    let fs = match shading {
        Shading::Average => "fs_average",
        Shading::Psi => "fs_psi",
    };
    // An explicit layout: each shading mode leaves some tables unused, and an automatic
    // layout would drop their bindings.
    let layout = LayoutEntries::new(wgpu::ShaderStages::VERTEX_FRAGMENT)
        .uniform(0)
        .read(4)
        .texture(5..=6, wgpu::TextureViewDimension::D1)
        .texture(7, wgpu::TextureViewDimension::D2)
        .read(MESH_BINDING..MESH_BINDING + arrays.bindings())
        .build(gpu, "fragment-pt pass 2");
    let pipeline_layout = gpu.pipeline_layout("fragment-pt pass 2", &[&layout]);
    // Back to front, premultiplied: dst = src + (1 − src.a) · dst.
    let pass2 = gpu.triangle_pipeline(
        "fragment-pt pass 2",
        &pipeline_layout,
        &module,
        "vs_main",
        fs,
        wgpu::TextureFormat::Rgba32Float,
        Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
        wgpu::ColorWrites::ALL,
    );
    let bind = gpu.bind_group(
        "fragment-pt pass 2",
        &layout,
        &[
            vec![
                storage(0, params),
                storage(4, order),
                view_entry(5, &tables.tf),
                view_entry(6, &tables.expt),
                view_entry(7, &tables.psi),
            ],
            arrays.bind_entries(),
        ]
        .concat(),
    );
    (pass2, bind)
}

/// The pass timestamps, where the adapter has timestamp queries.
fn timestamp_queries(gpu: &Gpu) -> Option<(wgpu::QuerySet, wgpu::Buffer)> {
    if !gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
        return None;
    }
    Some(gpu.query_set("fragment-pt timestamps", wgpu::QueryType::Timestamp, 4, 32))
}
