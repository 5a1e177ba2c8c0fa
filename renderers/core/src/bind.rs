//! The wgpu boilerplate every renderer repeated: bind-group layout entries, bind-group entries,
//! render targets, and arrays split across storage bindings ([`ChunkedBuffer`]).
//!
//! A storage binding covers at most `max_storage_buffer_binding_size` bytes (128 MiB on
//! lavapipe), so a 20 M-tet mesh's arrays (320 MB of tet indices, 640 MB of pass-1 records)
//! never fit one. [`ChunkedBuffer`] uploads such an array as several buffers of at most one
//! binding each and writes the WGSL that declares them and reads element `i` from the right
//! one (`NAME_at(i)`), so shaders index the whole array as before; a mesh that fits one
//! binding gets one buffer and the same shader code path.

use crate::gpu::{Gpu, Lifetime, MemoryLedger};

/// A uniform buffer entry of a bind-group layout.
pub fn uniform_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(binding, visibility, wgpu::BufferBindingType::Uniform)
}

/// The entry of a parameter block that a pass binds again (per pass, dispatch or draw): a
/// read-only storage buffer, not a uniform buffer. Lavapipe (Mesa 22.3) keeps about 64 KB for
/// every dispatch that sets a bind group holding a uniform buffer again and frees none of it
/// while the device lives, so memory grew with every frame (Teapot splatted at 256²: 529 MB
/// after one frame, 920 MB after nine; the mechanism inside the driver is not known).
/// docs/profile.md, "Uniform buffers on lavapipe".
pub fn params_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    storage_entry(binding, visibility, true)
}

/// A storage buffer entry of a bind-group layout.
pub fn storage_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    read_only: bool,
) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(
        binding,
        visibility,
        wgpu::BufferBindingType::Storage { read_only },
    )
}

/// A buffer entry of any binding type.
pub fn buffer_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BufferBindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// The same entry with a dynamic offset (a buffer entry; other entries are returned as given).
pub fn with_dynamic_offset(mut entry: wgpu::BindGroupLayoutEntry) -> wgpu::BindGroupLayoutEntry {
    if let wgpu::BindingType::Buffer {
        has_dynamic_offset, ..
    } = &mut entry.ty
    {
        *has_dynamic_offset = true;
    }
    entry
}

/// A float texture entry (not multisampled).
pub fn texture_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    filterable: bool,
    view_dimension: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayoutEntry {
    sampled_texture_entry(
        binding,
        visibility,
        wgpu::TextureSampleType::Float { filterable },
        view_dimension,
    )
}

/// A texture entry of any sample type (not multisampled).
pub fn sampled_texture_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    sample_type: wgpu::TextureSampleType,
    view_dimension: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension,
            multisampled: false,
        },
        count: None,
    }
}

/// A bind-group entry binding a texture view.
pub fn view_entry(binding: u32, view: &wgpu::TextureView) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::TextureView(view),
    }
}

/// A bind-group entry binding a whole buffer.
pub fn whole(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

/// A bind-group entry binding `size` bytes of a buffer from `offset` (a chunk of an array, or
/// one entry of a block read at dynamic offsets).
pub fn buffer_range(
    binding: u32,
    buffer: &wgpu::Buffer,
    offset: u64,
    size: u64,
) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer,
            offset,
            size: wgpu::BufferSize::new(size),
        }),
    }
}

/// Bind-group entries `first, first + 1, …` binding whole buffers.
pub fn whole_from<'a>(first: u32, buffers: &[&'a wgpu::Buffer]) -> Vec<wgpu::BindGroupEntry<'a>> {
    buffers
        .iter()
        .enumerate()
        .map(|(i, b)| whole(first + i as u32, b))
        .collect()
}

/// A pipeline layout of bind-group layouts `groups` (group `i` = `groups[i]`; `None` leaves a
/// group unused).
pub fn pipeline_layout(
    gpu: &Gpu,
    label: &str,
    groups: &[Option<&wgpu::BindGroupLayout>],
) -> wgpu::PipelineLayout {
    gpu.device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: groups,
            immediate_size: 0,
        })
}

/// A 2D texture of `w`×`h` recorded in `ledger` as per-frame memory, and its default view.
pub fn render_target(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    label: &str,
    (w, h): (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> anyhow::Result<(wgpu::Texture, wgpu::TextureView)> {
    let texture = ledger.texture(
        gpu,
        Lifetime::PerFrame,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        },
    )?;
    let view = texture.create_view(&Default::default());
    Ok((texture, view))
}

/// A persistent lookup table of `width` × `height` texels (`height` 1: a 1D texture) read by
/// `textureLoad`: tables a fragment shader indexes per fragment. A CPU backend gathers a
/// texel fetch across lanes, where llvmpipe loads storage in a fragment shader one lane at a
/// time; on an idle EPYC the difference for fragment PT's tables was within noise
/// (docs/roofline.md). `data` holds the texels' bytes, rows x fastest.
pub fn lookup_texture(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    label: &str,
    format: wgpu::TextureFormat,
    (width, height): (u32, u32),
    data: &[u8],
) -> anyhow::Result<wgpu::TextureView> {
    let texel = format.block_copy_size(None).unwrap_or(4);
    anyhow::ensure!(
        data.len() as u64 == texel as u64 * width as u64 * height as u64,
        "{label}: {} bytes for {width}x{height} texels of {texel} bytes",
        data.len()
    );
    let dimension = if height == 1 {
        wgpu::TextureDimension::D1
    } else {
        wgpu::TextureDimension::D2
    };
    let texture = texture_with_data(
        gpu,
        ledger,
        label,
        dimension,
        format,
        [width, height, 1],
        data,
    )?;
    Ok(texture.create_view(&Default::default()))
}

/// A persistent texture read by shaders only, of `[width, height, depth]` texels in `format`,
/// holding `data` (texels x fastest, then rows, then slices): what lookup tables need.
pub fn texture_with_data(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    label: &str,
    dimension: wgpu::TextureDimension,
    format: wgpu::TextureFormat,
    [width, height, depth]: [u32; 3],
    data: &[u8],
) -> anyhow::Result<wgpu::Texture> {
    let size = wgpu::Extent3d {
        width,
        height,
        depth_or_array_layers: depth,
    };
    let texture = ledger.texture(
        gpu,
        Lifetime::Persistent,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        },
    )?;
    gpu.queue.write_texture(
        texture.as_image_copy(),
        data,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(format.block_copy_size(None).unwrap_or(4) * width),
            rows_per_image: Some(height),
        },
        size,
    );
    Ok(texture)
}

/// WGSL of `fullscreen_vs`: one triangle over the whole viewport from `draw(0..3, 0..1)`,
/// without a vertex buffer. Included by the shaders of per-pixel passes (the splatter's
/// composite, the ray caster's count of peeling candidates).
pub const FULLSCREEN_WGSL: &str = include_str!("fullscreen.wgsl");

/// Begins a render pass into one colour attachment, cleared to transparent black first when
/// `clear`, kept (`store`) or thrown away after the pass (a dummy attachment of passes that
/// write storage only), with optional timestamps.
pub fn color_pass<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    label: &str,
    view: &wgpu::TextureView,
    clear: bool,
    store: bool,
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
) -> wgpu::RenderPass<'e> {
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: if clear {
                    wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
                } else {
                    wgpu::LoadOp::Load
                },
                store: if store {
                    wgpu::StoreOp::Store
                } else {
                    wgpu::StoreOp::Discard
                },
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// Fails, with the figures, when a pipeline needs more storage bindings per shader stage than
/// the adapter has.
pub fn check_storage_bindings(gpu: &Gpu, label: &str, needed: u32) -> anyhow::Result<()> {
    let max = gpu.limits.max_storage_buffers_per_shader_stage;
    if needed > max {
        anyhow::bail!(
            "{label}: needs {needed} storage bindings in one shader stage, the adapter allows \
             {max} (max_storage_buffers_per_shader_stage; each binding holds at most {} bytes)",
            gpu.max_storage_binding()
        );
    }
    Ok(())
}

/// WGSL declaring `chunks` storage arrays `NAME_0 …` of `TY` at `@group(group) @binding(first
/// ..)`, `per_chunk` elements each (the last may hold fewer), and `fn NAME_at(i: u32) -> TY`
/// (and `fn NAME_set(i: u32, v: TY)` when writable) that index them as one array: what
/// [`ChunkedBuffer::wgsl`] writes, for arrays bound in any chunks (e.g. [`range_entries`]).
pub fn chunked_wgsl(
    name: &str,
    ty: &str,
    group: u32,
    first: u32,
    chunks: u32,
    per_chunk: u64,
    read_only: bool,
) -> String {
    let access = if read_only { "read" } else { "read_write" };
    let n = chunks.max(1);
    let mut s = String::new();
    for i in 0..n {
        s += &format!(
            "@group({group}) @binding({}) var<storage, {access}> {name}_{i}: array<{ty}>;\n",
            first + i
        );
    }
    let per = per_chunk.min(u32::MAX as u64);
    let mut get = format!("fn {name}_at(i: u32) -> {ty} {{\n");
    let mut set = format!("fn {name}_set(i: u32, v: {ty}) {{\n");
    if n == 1 {
        get += &format!("    return {name}_0[i];\n}}\n");
        set += &format!("    {name}_0[i] = v;\n}}\n");
    } else {
        let head =
            format!("    let c = i / {per}u;\n    let j = i - c * {per}u;\n    switch c {{\n");
        get += &head;
        set += &head;
        for i in 0..n {
            let case = if i + 1 == n {
                "default".to_string()
            } else {
                format!("case {i}u")
            };
            get += &format!("        {case}: {{ return {name}_{i}[j]; }}\n");
            set += &format!("        {case}: {{ {name}_{i}[j] = v; }}\n");
        }
        get += "    }\n}\n";
        set += "    }\n}\n";
    }
    s += &get;
    if !read_only {
        s += &set;
    }
    s
}

/// Bind-group entries `first ..` that bind one buffer as `chunks` arrays of `per_chunk`
/// elements of `elem_bytes` each (the chunks [`chunked_wgsl`] declares), covering its first
/// `len` elements: a buffer larger than one storage binding, sorted or written whole by a
/// shader through `NAME_at` / `NAME_set`. A chunk past `len` binds the first element (its
/// binding must exist; no index reaches it). `per_chunk × elem_bytes` must be a multiple of
/// the storage offset alignment (256 bytes), as [`crate::Gpu::max_storage_binding`] is.
pub fn range_entries(
    first: u32,
    buffer: &wgpu::Buffer,
    elem_bytes: u64,
    per_chunk: u64,
    chunks: u32,
    len: u64,
) -> Vec<wgpu::BindGroupEntry<'_>> {
    (0..chunks.max(1))
        .map(|c| {
            let start = c as u64 * per_chunk;
            let end = ((c as u64 + 1) * per_chunk).min(len);
            let (offset, elements) = if end > start {
                (start * elem_bytes, end - start)
            } else {
                (0, 1)
            };
            buffer_range(first + c, buffer, offset, elements * elem_bytes)
        })
        .collect()
}

/// An array of fixed-size elements split across buffers of at most one storage binding each.
pub struct ChunkedBuffer {
    pub buffers: Vec<wgpu::Buffer>,
    /// Elements per buffer (the last may hold fewer).
    pub per_chunk: u64,
    /// Elements in all.
    pub len: u64,
    pub elem_bytes: u64,
}

impl ChunkedBuffer {
    /// Elements per chunk for `elem_bytes`-byte elements under `max_binding` bytes.
    pub fn per_chunk(elem_bytes: u64, max_binding: u64) -> u64 {
        (max_binding / elem_bytes.max(1)).max(1)
    }

    /// Uploads `data` (whole elements of `elem_bytes`) in chunks of at most `max_binding`
    /// bytes; every buffer is recorded in `ledger` under `label`.
    #[allow(clippy::too_many_arguments)]
    pub fn with_data(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        label: &str,
        lifetime: Lifetime,
        data: &[u8],
        elem_bytes: u64,
        max_binding: u64,
        usage: wgpu::BufferUsages,
    ) -> anyhow::Result<ChunkedBuffer> {
        let len = data.len() as u64 / elem_bytes;
        debug_assert_eq!(len * elem_bytes, data.len() as u64);
        let per = Self::per_chunk(elem_bytes, max_binding);
        let buffers = crate::gpu::chunk_ranges(len.max(1), elem_bytes, per * elem_bytes)
            .into_iter()
            .map(|r| {
                let lo = (r.start * elem_bytes).min(data.len() as u64) as usize;
                let hi = (r.end * elem_bytes).min(data.len() as u64) as usize;
                ledger.buffer_init(gpu, label, lifetime, &data[lo..hi], usage)
            })
            .collect::<anyhow::Result<_>>()?;
        Ok(ChunkedBuffer {
            buffers,
            per_chunk: per,
            len,
            elem_bytes,
        })
    }

    /// `len` uninitialised elements (written on the GPU) in chunks of at most `max_binding`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        label: &str,
        lifetime: Lifetime,
        len: u64,
        elem_bytes: u64,
        max_binding: u64,
        usage: wgpu::BufferUsages,
    ) -> anyhow::Result<ChunkedBuffer> {
        let per = Self::per_chunk(elem_bytes, max_binding);
        let buffers = crate::gpu::chunk_ranges(len.max(1), elem_bytes, per * elem_bytes)
            .into_iter()
            .map(|r| ledger.buffer(gpu, label, lifetime, (r.end - r.start) * elem_bytes, usage))
            .collect::<anyhow::Result<_>>()?;
        Ok(ChunkedBuffer {
            buffers,
            per_chunk: per,
            len,
            elem_bytes,
        })
    }

    /// Storage bindings this array takes.
    pub fn bindings(&self) -> u32 {
        self.buffers.len() as u32
    }

    /// Layout entries `first ..` for the chunks.
    pub fn layout_entries(
        &self,
        first: u32,
        visibility: wgpu::ShaderStages,
        read_only: bool,
    ) -> Vec<wgpu::BindGroupLayoutEntry> {
        (0..self.bindings())
            .map(|i| storage_entry(first + i, visibility, read_only))
            .collect()
    }

    /// Bind-group entries `first ..` for the chunks.
    pub fn bind_entries(&self, first: u32) -> Vec<wgpu::BindGroupEntry<'_>> {
        let refs: Vec<&wgpu::Buffer> = self.buffers.iter().collect();
        whole_from(first, &refs)
    }

    /// WGSL declaring the chunks as `NAME_0 …` at `@group(group) @binding(first ..)` and
    /// `fn NAME_at(i: u32) -> TY` (and `fn NAME_set(i: u32, v: TY)` when writable).
    pub fn wgsl(&self, name: &str, ty: &str, group: u32, first: u32, read_only: bool) -> String {
        chunked_wgsl(
            name,
            ty,
            group,
            first,
            self.bindings(),
            self.per_chunk,
            read_only,
        )
    }

    /// Writes host data starting at element `first` (may span chunks).
    pub fn write(&self, gpu: &Gpu, first: u64, data: &[u8]) {
        let n = data.len() as u64 / self.elem_bytes;
        let mut done = 0u64;
        while done < n {
            let e = first + done;
            let c = (e / self.per_chunk) as usize;
            let local = e - c as u64 * self.per_chunk;
            let take = (self.per_chunk - local).min(n - done);
            let lo = (done * self.elem_bytes) as usize;
            let hi = ((done + take) * self.elem_bytes) as usize;
            gpu.queue
                .write_buffer(&self.buffers[c], local * self.elem_bytes, &data[lo..hi]);
            done += take;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The generated accessor covers chunk boundaries like `chunk_ranges` does.
    #[test]
    fn wgsl_accessor_has_one_case_per_chunk() {
        let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
        let mut ledger = MemoryLedger::default();
        let data: Vec<u32> = (0..10).collect();
        let c = ChunkedBuffer::with_data(
            &gpu,
            &mut ledger,
            "t",
            Lifetime::Persistent,
            bytemuck::cast_slice(&data),
            4,
            16,
            wgpu::BufferUsages::STORAGE,
        )
        .unwrap();
        assert_eq!((c.bindings(), c.per_chunk, c.len), (3, 4, 10));
        assert_eq!(ledger.persistent, 16 + 16 + 16);
        let w = c.wgsl("x", "u32", 0, 5, true);
        assert!(w.contains("@binding(7) var<storage, read> x_2"), "{w}");
        assert!(w.contains("case 1u: { return x_1[j]; }"), "{w}");
        assert!(w.contains("default: { return x_2[j]; }"), "{w}");
        assert!(!w.contains("x_set"));
        // The generated WGSL compiles and reads every element from the right chunk.
        let src = format!(
            "{}@group(0) @binding(0) var<storage, read_write> out: array<u32>;\n\
             @compute @workgroup_size(1) fn main() {{ for (var i = 0u; i < 10u; i++) {{ out[i] = x_at(i); }} }}",
            c.wgsl("x", "u32", 0, 1, true)
        );
        let module = gpu.shader("chunk test", &src);
        let pipe = gpu.compute_pipeline("chunk test", None, &module, "main");
        let out = ledger
            .buffer(
                &gpu,
                "out",
                Lifetime::PerFrame,
                40,
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            )
            .unwrap();
        let mut entries = vec![whole(0, &out)];
        entries.extend(c.bind_entries(1));
        let bg = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipe.get_bind_group_layout(0),
            entries: &entries,
        });
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipe);
            pass.set_bind_group(0, &bg, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        gpu.queue.submit([enc.finish()]);
        let back = gpu.read_buffer(&out, 0, 40).unwrap();
        assert_eq!(bytemuck::cast_slice::<u8, u32>(&back), &data[..]);
    }
}

/// Uniform or storage entries addressed with dynamic offsets are this far apart (the largest
/// `min_uniform_buffer_offset_alignment` and `min_storage_buffer_offset_alignment` wgpu
/// allows).
pub const UNIFORM_STRIDE: u64 = 256;

/// `items` laid out one every [`UNIFORM_STRIDE`] bytes: the contents of a uniform or storage
/// buffer whose entry `i` is bound at dynamic offset `i × UNIFORM_STRIDE`.
pub fn strided_uniforms<T: bytemuck::Pod>(items: &[T]) -> Vec<u8> {
    let stride = UNIFORM_STRIDE as usize;
    assert!(
        std::mem::size_of::<T>() <= stride,
        "a uniform entry over {stride} bytes"
    );
    let mut out = vec![0u8; items.len() * stride];
    for (entry, item) in out.chunks_exact_mut(stride).zip(items) {
        entry[..std::mem::size_of::<T>()].copy_from_slice(bytemuck::bytes_of(item));
    }
    out
}

/// Vertices per draw call in a render pass over a whole mesh ([`crate::gpu::MAX_TRIANGLES_PER_PASS`]
/// says why they are bounded; a multiple of 12: whole triangles, and whole
/// tets of four triangles).
pub const MAX_VERTICES_PER_DRAW: u32 = 3 * (1 << 18);

/// `vertices` cut into the ranges of consecutive render passes of at most `triangles_per_pass`
/// triangles (a multiple of 4: [`crate::Gpu::triangles_per_pass`]), in order; one empty range
/// when there is nothing to draw (the caller's one pass still clears its target).
pub fn pass_slices(
    vertices: std::ops::Range<u32>,
    triangles_per_pass: u32,
) -> Vec<std::ops::Range<u32>> {
    let per_pass = 3 * triangles_per_pass.max(4);
    let mut out: Vec<_> = vertices
        .clone()
        .step_by(per_pass as usize)
        .map(|start| start..(start + per_pass).min(vertices.end))
        .collect();
    if out.is_empty() {
        out.push(vertices.start..vertices.start);
    }
    out
}

/// Draws `vertices` (one instance) in consecutive calls of at most [`MAX_VERTICES_PER_DRAW`]:
/// the same primitives in the same order.
pub fn draw_in_slices(pass: &mut wgpu::RenderPass<'_>, vertices: std::ops::Range<u32>) {
    for start in vertices.clone().step_by(MAX_VERTICES_PER_DRAW as usize) {
        pass.draw(
            start..(start + MAX_VERTICES_PER_DRAW).min(vertices.end),
            0..1,
        );
    }
}

#[cfg(test)]
mod slice_tests {
    use super::*;

    #[test]
    fn passes_and_draws_cover_the_vertices_in_order_in_whole_tets() {
        let per_pass = 3 * crate::gpu::MAX_TRIANGLES_PER_PASS;
        let p = crate::gpu::MAX_TRIANGLES_PER_PASS;
        assert_eq!(pass_slices(0..0, p), vec![0..0]);
        assert_eq!(pass_slices(0..12, p), vec![0..12]);
        assert_eq!(pass_slices(0..30, 4), vec![0..12, 12..24, 24..30]);
        assert_eq!(
            pass_slices(0..2 * per_pass + 12, p),
            vec![
                0..per_pass,
                per_pass..2 * per_pass,
                2 * per_pass..2 * per_pass + 12
            ]
        );
        assert_eq!(per_pass % 12, 0);
        assert_eq!(MAX_VERTICES_PER_DRAW % 12, 0);
        assert_eq!(per_pass % MAX_VERTICES_PER_DRAW, 0);
    }

    #[test]
    fn strided_uniforms_put_entry_i_at_i_strides() {
        let bytes = strided_uniforms(&[[1u32, 2, 3, 4], [5, 6, 7, 8]]);
        assert_eq!(bytes.len(), 2 * UNIFORM_STRIDE as usize);
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
        assert_eq!((word(0), word(12)), (1, 4));
        assert_eq!(word(16), 0);
        assert_eq!((word(256), word(268)), (5, 8));
    }
}
