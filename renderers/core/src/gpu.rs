//! The headless wgpu context every GPU algorithm shares, GPU timing by timestamp queries, memory
//! accounting, readback, and splitting of large arrays across storage bindings.
//!
//! Runs on any backend: Vulkan through Mesa's lavapipe where there is no GPU (CI, developers'
//! machines), Vulkan/Metal/DX12 on real hardware. Every result row records which.

use std::sync::mpsc;
use std::time::{Duration, Instant};

use anyhow::{anyhow, Context};
use serde::{Deserialize, Serialize};

use crate::image::Image;

/// Who rendered: recorded in every result row.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdapterDescription {
    pub name: String,
    pub backend: String,
    pub device_type: String,
    pub driver: String,
    pub driver_info: String,
}

impl AdapterDescription {
    /// A CPU backend (`wgpu::DeviceType::Cpu`, recorded as its `Debug` name), such as
    /// lavapipe: it runs a workgroup on one core and a shader's lanes as SIMD batches.
    pub fn is_cpu(&self) -> bool {
        self.device_type == "Cpu"
    }
}

/// The device, its queue and what it can do.
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter: AdapterDescription,
    pub features: wgpu::Features,
    pub limits: wgpu::Limits,
    /// Triangles per render pass when a whole mesh is drawn
    /// ([`MAX_TRIANGLES_PER_PASS`] unless the request asked for fewer).
    pub triangles_per_pass: u32,
    /// Mappable buffers of earlier readbacks, reused by the next ([`Gpu::read_buffer`]): a
    /// frame that reads its counters back would otherwise allocate one every frame, which a
    /// real application keeps.
    staging: std::sync::Mutex<Vec<wgpu::Buffer>>,
    /// Mappable buffers created for readbacks so far (what the reuse saves; tests read it).
    staging_created: std::sync::atomic::AtomicU64,
}

/// Readback buffers kept for reuse at most (the rest are dropped when returned).
const STAGING_KEPT: usize = 8;

/// Features used when present; none is required, each algorithm checks what it needs.
fn wanted_features() -> wgpu::Features {
    wgpu::Features::TIMESTAMP_QUERY
        | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
        | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES
        | wgpu::Features::SHADER_F64
        | wgpu::Features::FLOAT32_FILTERABLE
        | wgpu::Features::FLOAT32_BLENDABLE
        | wgpu::Features::VERTEX_WRITABLE_STORAGE
        | wgpu::Features::INDIRECT_FIRST_INSTANCE
        | wgpu::Features::DEPTH32FLOAT_STENCIL8
        | wgpu::Features::SHADER_EARLY_DEPTH_TEST
}

/// What to ask of the adapter beyond "everything it offers": the paths a given machine would
/// not take on its own. Tests ask for small storage bindings (the chunked paths engage on a
/// mesh of modest size, and wgpu then refuses any binding past the limit, as a GPU with that
/// limit would) and for no timestamp queries (frames without `gpu_ms`, as on adapters that
/// lack them); `scripts/validate.sh` sets the same through the environment
/// ([`DeviceRequest::from_env`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DeviceRequest {
    /// Request at most this `max_storage_buffer_binding_size` (bytes, rounded down to a
    /// multiple of 256, at least 256); `None`: the adapter's own.
    pub max_storage_binding: Option<u64>,
    /// Leave the timestamp-query features off even where the adapter has them.
    pub no_timestamps: bool,
    /// Draw whole meshes in render passes of at most this many triangles (rounded down to a
    /// multiple of 4, at least 4); `None`: [`MAX_TRIANGLES_PER_PASS`].
    pub max_triangles_per_pass: Option<u32>,
}

/// Environment variable of [`DeviceRequest::max_storage_binding`] (bytes).
pub const ENV_MAX_STORAGE_BINDING: &str = "TETBENCH_MAX_STORAGE_BINDING";
/// Environment variable of [`DeviceRequest::no_timestamps`] (`off` turns them off).
pub const ENV_TIMESTAMPS: &str = "TETBENCH_TIMESTAMPS";
/// Environment variable of [`DeviceRequest::max_triangles_per_pass`].
pub const ENV_MAX_TRIANGLES_PER_PASS: &str = "TETBENCH_MAX_TRIANGLES_PER_PASS";

impl DeviceRequest {
    /// The request `TETBENCH_MAX_STORAGE_BINDING=BYTES` and `TETBENCH_TIMESTAMPS=off` describe
    /// (neither set: the adapter as it is).
    pub fn from_env() -> anyhow::Result<DeviceRequest> {
        Self::from_vars(|k| std::env::var(k).ok())
    }

    /// [`DeviceRequest::from_env`] with `lookup` in place of the environment.
    pub fn from_vars(lookup: impl Fn(&str) -> Option<String>) -> anyhow::Result<DeviceRequest> {
        let var = |k: &str| lookup(k).filter(|v| !v.trim().is_empty());
        let max_storage_binding = match var(ENV_MAX_STORAGE_BINDING) {
            None => None,
            Some(v) => Some(v.trim().parse::<u64>().map_err(|_| {
                anyhow!("{ENV_MAX_STORAGE_BINDING}={v:?}: expected a number of bytes")
            })?),
        };
        let no_timestamps = match var(ENV_TIMESTAMPS).as_deref().map(str::trim) {
            None | Some("on") => false,
            Some("off") => true,
            Some(v) => anyhow::bail!("{ENV_TIMESTAMPS}={v:?}: expected on or off"),
        };
        let max_triangles_per_pass = match var(ENV_MAX_TRIANGLES_PER_PASS) {
            None => None,
            Some(v) => Some(v.trim().parse::<u32>().map_err(|_| {
                anyhow!("{ENV_MAX_TRIANGLES_PER_PASS}={v:?}: expected a number of triangles")
            })?),
        };
        Ok(DeviceRequest {
            max_storage_binding,
            no_timestamps,
            max_triangles_per_pass,
        })
    }

    /// What the request changed, for the adapter's description (so that rows measured on a
    /// restricted device say so); empty when nothing.
    fn note(&self, limits: &wgpu::Limits) -> String {
        let mut parts = vec![];
        if self.max_storage_binding.is_some() {
            parts.push(format!(
                "max_storage_buffer_binding_size requested as {}",
                limits.max_storage_buffer_binding_size
            ));
        }
        if self.no_timestamps {
            parts.push("timestamp queries off".to_string());
        }
        if let Some(n) = self.max_triangles_per_pass {
            parts.push(format!(
                "render passes of at most {} triangles",
                Self::pass_size(n)
            ));
        }
        parts.join(", ")
    }

    fn pass_size(n: u32) -> u32 {
        (n / 4 * 4).max(4)
    }
}

/// Instance flags: wgpu's defaults for the build without backend validation, then the
/// `WGPU_*` environment variables (`WGPU_VALIDATION=1`, `WGPU_DEBUG=1`, …) as wgpu documents
/// them. wgpu's default turns the Khronos validation layer on in every debug build where the
/// layer is installed, which would slow every test on a machine that once ran
/// `scripts/validate.sh`; here validation is asked for, never implied by the build profile.
/// (wgpu's own API validation is always on: a violation is an error whatever the flags.)
pub fn instance_flags() -> wgpu::InstanceFlags {
    (wgpu::InstanceFlags::from_build_config() - wgpu::InstanceFlags::VALIDATION).with_env()
}

impl Gpu {
    /// Opens the first adapter (high-performance preferred; software adapters allowed), as
    /// the environment asks ([`DeviceRequest::from_env`]; normally: all it offers).
    pub fn new() -> anyhow::Result<Gpu> {
        Self::with_request(&DeviceRequest::from_env()?)
    }

    /// Opens the first adapter with the features and limits `request` allows.
    pub fn with_request(request: &DeviceRequest) -> anyhow::Result<Gpu> {
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        descriptor.flags = instance_flags();
        let instance = wgpu::Instance::new(descriptor);
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            ..Default::default()
        }))
        .map_err(|e| {
            anyhow!(
                "no GPU adapter found ({e}). On a machine without a GPU install Mesa's software \
                 Vulkan driver: apt-get install -y mesa-vulkan-drivers libvulkan1"
            )
        })?;
        let info = adapter.get_info();
        let mut features = adapter.features() & wanted_features();
        if request.no_timestamps {
            features.remove(
                wgpu::Features::TIMESTAMP_QUERY
                    | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
                    | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES,
            );
        }
        let mut limits = adapter.limits();
        if let Some(bytes) = request.max_storage_binding {
            limits.max_storage_buffer_binding_size = (bytes & !255)
                .max(256)
                .min(limits.max_storage_buffer_binding_size);
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("tetbench"),
            required_features: features,
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .context("requesting the GPU device")?;
        // What the device enforces, which is what the algorithms must plan for.
        let limits = device.limits();
        let note = request.note(&limits);
        let driver_info = if note.is_empty() {
            info.driver_info.clone()
        } else {
            format!("{} (tetbench: {note})", info.driver_info)
        };
        Ok(Gpu {
            device,
            queue,
            adapter: AdapterDescription {
                name: info.name.clone(),
                backend: format!("{:?}", info.backend).to_lowercase(),
                device_type: format!("{:?}", info.device_type),
                driver: info.driver.clone(),
                driver_info,
            },
            features,
            limits,
            triangles_per_pass: request
                .max_triangles_per_pass
                .map_or(MAX_TRIANGLES_PER_PASS, DeviceRequest::pass_size),
            staging: Default::default(),
            staging_created: Default::default(),
        })
    }

    pub fn has_timestamps(&self) -> bool {
        self.features.contains(
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS,
        )
    }

    /// Largest storage buffer one binding may cover (128 MiB on lavapipe), rounded down to a
    /// multiple of 256 bytes so chunks stay aligned for any element size up to 256.
    pub fn max_storage_binding(&self) -> u64 {
        let m = self
            .limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size);
        m & !255
    }

    /// Checks a buffer of `size` bytes against the adapter's `max_buffer_size`, so that an
    /// oversized allocation fails its row with the figures instead of a wgpu validation panic.
    pub fn check_buffer(&self, label: &str, size: u64) -> anyhow::Result<()> {
        let max = self.limits.max_buffer_size;
        if size > max {
            anyhow::bail!(
                "needs {size} bytes ({:.1} MiB) for buffer {label:?}, the adapter allows {max} \
                 bytes ({:.1} MiB) per buffer (max_buffer_size); a smaller viewport or mesh, or a \
                 split of this buffer into {} parts, would fit",
                size as f64 / 1048576.0,
                max as f64 / 1048576.0,
                size.div_ceil(max.max(1))
            );
        }
        Ok(())
    }

    /// Checks a texture's extent against the adapter's dimension limits (2D or 3D).
    pub fn check_texture(&self, desc: &wgpu::TextureDescriptor) -> anyhow::Result<()> {
        let s = desc.size;
        let label = desc.label.unwrap_or("texture");
        let (max, limit) = match desc.dimension {
            wgpu::TextureDimension::D3 => (
                self.limits.max_texture_dimension_3d,
                "max_texture_dimension_3d",
            ),
            wgpu::TextureDimension::D2 => (
                self.limits.max_texture_dimension_2d,
                "max_texture_dimension_2d",
            ),
            wgpu::TextureDimension::D1 => (
                self.limits.max_texture_dimension_1d,
                "max_texture_dimension_1d",
            ),
        };
        let depth = if desc.dimension == wgpu::TextureDimension::D3 {
            s.depth_or_array_layers
        } else {
            1
        };
        if s.width > max || s.height > max || depth > max {
            anyhow::bail!(
                "needs a {}×{}×{} texture for {label:?}, the adapter allows {max} texels per side \
                 ({limit})",
                s.width,
                s.height,
                s.depth_or_array_layers
            );
        }
        Ok(())
    }

    /// Blocks until all submitted work is done.
    pub fn wait(&self) -> anyhow::Result<()> {
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: None,
            })
            .map(|_| ())
            .map_err(|e| anyhow!("waiting for the GPU: {e}"))
    }

    /// Loads a WGSL module; `source` is normally `include_str!("name.wgsl")` of a shader file
    /// beside the algorithm's Rust.
    pub fn shader(&self, label: &str, source: &str) -> wgpu::ShaderModule {
        self.device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            })
    }

    /// A compute pipeline running `entry` of `module`; with no `layout`, the bind group layouts
    /// are derived from the shader.
    pub fn compute_pipeline(
        &self,
        label: &str,
        layout: Option<&wgpu::PipelineLayout>,
        module: &wgpu::ShaderModule,
        entry: &str,
    ) -> wgpu::ComputePipeline {
        self.device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout,
                module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
    }

    /// The render pipeline every cell-projection pass here uses: vertices pulled from storage
    /// (no vertex buffers), a triangle list drawn from both sides (no culling: a projected
    /// cell's winding says nothing about visibility), no depth test (the visibility order does
    /// that), one colour target of `format`.
    #[allow(clippy::too_many_arguments)]
    pub fn triangle_pipeline(
        &self,
        label: &str,
        layout: &wgpu::PipelineLayout,
        module: &wgpu::ShaderModule,
        vertex_entry: &str,
        fragment_entry: &str,
        format: wgpu::TextureFormat,
        blend: Option<wgpu::BlendState>,
        write_mask: wgpu::ColorWrites,
    ) -> wgpu::RenderPipeline {
        self.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some(vertex_entry),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module,
                    entry_point: Some(fragment_entry),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend,
                        write_mask,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
    }

    /// Copies a buffer range to the host (blocking).
    pub fn read_buffer(
        &self,
        buffer: &wgpu::Buffer,
        offset: u64,
        size: u64,
    ) -> anyhow::Result<Vec<u8>> {
        let mut waited = Duration::ZERO;
        self.read_buffer_timed(buffer, offset, size, &mut waited)
    }

    /// [`Gpu::read_buffer`] that adds the time spent waiting for the map to `waited` (the
    /// rest, encoding the copy and copying the mapped bytes, is host work; see
    /// [`crate::FrameClock`]).
    pub fn read_buffer_timed(
        &self,
        buffer: &wgpu::Buffer,
        offset: u64,
        size: u64,
        waited: &mut Duration,
    ) -> anyhow::Result<Vec<u8>> {
        let staging = self.take_staging(size);
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(buffer, offset, &staging, 0, size);
        // The submit counts as waiting (see FrameClock::submit).
        let t = Instant::now();
        self.queue.submit([enc.finish()]);
        *waited += t.elapsed();
        let data = self.map_and_copy(&staging, size, waited);
        self.return_staging(staging);
        data
    }

    /// A mappable buffer of at least `size` bytes: the smallest kept one that fits, else a new
    /// one (sizes rounded up to 4 KiB, so that a frame's readbacks of slightly different
    /// sizes share one).
    pub fn take_staging(&self, size: u64) -> wgpu::Buffer {
        let mut kept = self.staging.lock().unwrap_or_else(|e| e.into_inner());
        let fit = kept
            .iter()
            .enumerate()
            .filter(|(_, b)| b.size() >= size)
            .min_by_key(|(_, b)| b.size())
            .map(|(i, _)| i);
        if let Some(i) = fit {
            return kept.swap_remove(i);
        }
        drop(kept);
        self.staging_created
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: size.max(1).next_multiple_of(4096),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Gives an unmapped readback buffer back for reuse.
    pub fn return_staging(&self, buffer: wgpu::Buffer) {
        let mut kept = self.staging.lock().unwrap_or_else(|e| e.into_inner());
        if kept.len() < STAGING_KEPT {
            kept.push(buffer);
        }
    }

    /// Mappable buffers created for readbacks since the device was opened.
    pub fn staging_buffers_created(&self) -> u64 {
        self.staging_created
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Maps the first `size` bytes of `staging` (after the work that fills it was submitted),
    /// copies them out and unmaps it; the wait for the map is added to `waited`.
    pub fn map_and_copy(
        &self,
        staging: &wgpu::Buffer,
        size: u64,
        waited: &mut Duration,
    ) -> anyhow::Result<Vec<u8>> {
        let (tx, rx) = mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, ..size, move |r| {
            let _ = tx.send(r);
        });
        let t = Instant::now();
        let r = self.wait();
        *waited += t.elapsed();
        r?;
        rx.recv()
            .map_err(|_| anyhow!("readback callback dropped"))?
            .map_err(|e| anyhow!("mapping readback buffer: {e}"))?;
        let data = staging
            .get_mapped_range(..size)
            .map_err(|e| anyhow!("mapped range: {e:?}"))?
            .to_vec();
        staging.unmap();
        Ok(data)
    }

    /// Reads an `Rgba32Float` texture (premultiplied linear) into an [`Image`].
    pub fn read_rgba32f(&self, texture: &wgpu::Texture) -> anyhow::Result<Image> {
        let (w, h) = (texture.width(), texture.height());
        let bytes = self.read_texture_layer(texture, 0)?;
        let mut img = Image::new(w, h);
        img.pixels.copy_from_slice(bytemuck::cast_slice(&bytes));
        Ok(img)
    }

    /// Reads layer `layer` of a 2D (array) texture of 16-byte texels, rows unpadded.
    pub fn read_texture_layer(
        &self,
        texture: &wgpu::Texture,
        layer: u32,
    ) -> anyhow::Result<Vec<u8>> {
        let (w, h) = (texture.width(), texture.height());
        let unpadded = w as u64 * 16;
        let padded = unpadded.div_ceil(256) * 256;
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("image readback"),
            size: padded * h as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: layer,
                },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded as u32),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        self.queue.submit([enc.finish()]);
        let mut waited = Duration::ZERO;
        let bytes = self.map_and_copy(&staging, staging.size(), &mut waited)?;
        let mut out = Vec::with_capacity((unpadded * h as u64) as usize);
        for y in 0..h as usize {
            out.extend_from_slice(
                &bytes[y * padded as usize..y * padded as usize + unpadded as usize],
            );
        }
        Ok(out)
    }
}

/// Where an allocation belongs in the memory report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lifetime {
    /// Lives as long as the mesh: counted in bytes/tet.
    Persistent,
    /// Scratch of one frame (k-buffers, sort buffers, render targets).
    PerFrame,
}

/// Triangles per render pass when a whole mesh is drawn. Lavapipe bins every triangle of a
/// pass before it rasterises the pass's tiles, and shades and bins a draw's vertices whole, so
/// one pass or one draw over a large mesh holds host memory in proportion to it. Measured on
/// `box:2m` at 512² (resident peak of the run): HAVS's 4 M faces in one draw 1.68 GB, in draws
/// of 262,144 triangles 0.80 GB; GATOR (draws of 1,024 tets already) in one pass 0.95 GB, in
/// passes of 262,144 tets 0.57 GB, frame times within their spread (docs/profile.md).
/// `crate::bind::pass_slices` cuts a mesh's vertices into such passes.
pub const MAX_TRIANGLES_PER_PASS: u32 = 1 << 20;

/// Largest piece [`MemoryLedger::buffer_init`] stages at once (see there).
pub const UPLOAD_CHUNK: usize = 16 << 20;

/// Counts every buffer and texture an algorithm allocates.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MemoryLedger {
    pub persistent: u64,
    pub per_frame: u64,
    pub entries: Vec<(String, Lifetime, u64)>,
}

impl MemoryLedger {
    pub fn record(&mut self, label: &str, lifetime: Lifetime, bytes: u64) {
        match lifetime {
            Lifetime::Persistent => self.persistent += bytes,
            Lifetime::PerFrame => self.per_frame += bytes,
        }
        self.entries.push((label.to_string(), lifetime, bytes));
    }

    /// Creates a buffer and records it; fails, naming the buffer, the bytes it needs and the
    /// adapter's limit, where wgpu would raise a validation error.
    pub fn buffer(
        &mut self,
        gpu: &Gpu,
        label: &str,
        lifetime: Lifetime,
        size: u64,
        usage: wgpu::BufferUsages,
    ) -> anyhow::Result<wgpu::Buffer> {
        let size = size.max(16).div_ceil(4) * 4;
        gpu.check_buffer(label, size)?;
        self.record(label, lifetime, size);
        Ok(gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage,
            mapped_at_creation: false,
        }))
    }

    /// Creates a buffer holding `data` and records it; data past [`UPLOAD_CHUNK`] bytes is
    /// uploaded piece by piece, each piece's staging copy released before the next.
    pub fn buffer_init(
        &mut self,
        gpu: &Gpu,
        label: &str,
        lifetime: Lifetime,
        data: &[u8],
        usage: wgpu::BufferUsages,
    ) -> anyhow::Result<wgpu::Buffer> {
        let buf = self.buffer(
            gpu,
            label,
            lifetime,
            data.len() as u64,
            usage | wgpu::BufferUsages::COPY_DST,
        )?;
        if data.len() <= UPLOAD_CHUNK {
            gpu.queue.write_buffer(&buf, 0, data);
        } else {
            // Each write is staged in a copy of its bytes until a submission carries it; in
            // pieces, each flushed and waited for, the copies of a large upload never add up
            // (on lavapipe, where "device" memory is host memory, a mesh's buffers were
            // otherwise held three times during prepare: the caller's array, the staging copy
            // and the buffer).
            for (i, piece) in data.chunks(UPLOAD_CHUNK).enumerate() {
                gpu.queue
                    .write_buffer(&buf, (i * UPLOAD_CHUNK) as u64, piece);
                gpu.queue.submit([]);
                gpu.wait()?;
            }
        }
        Ok(buf)
    }

    /// Creates a texture and records its size; fails on sizes the adapter does not allow.
    pub fn texture(
        &mut self,
        gpu: &Gpu,
        lifetime: Lifetime,
        desc: &wgpu::TextureDescriptor,
    ) -> anyhow::Result<wgpu::Texture> {
        gpu.check_texture(desc)?;
        let texel = desc.format.block_copy_size(None).unwrap_or(4) as u64;
        let s = desc.size;
        self.record(
            desc.label.unwrap_or("texture"),
            lifetime,
            texel * s.width as u64 * s.height as u64 * s.depth_or_array_layers as u64,
        );
        Ok(gpu.device.create_texture(desc))
    }

    pub fn total(&self) -> u64 {
        self.persistent + self.per_frame
    }

    /// Bytes of the buffers and textures whose label starts with `prefix`: what one kind of
    /// data takes on the device, as allocated.
    pub fn bytes_labelled(&self, prefix: &str) -> u64 {
        self.entries
            .iter()
            .filter(|(label, _, _)| label.starts_with(prefix))
            .map(|(_, _, bytes)| bytes)
            .sum()
    }
}

/// Splits `count` elements of `element_bytes` each into ranges that fit one storage binding.
/// Large meshes (20 M tets = 320 MB of indices) are drawn chunk by chunk, never refused.
pub fn chunk_ranges(count: u64, element_bytes: u64, max_binding: u64) -> Vec<std::ops::Range<u64>> {
    let per = (max_binding / element_bytes).max(1);
    (0..count.div_ceil(per))
        .map(|i| i * per..((i + 1) * per).min(count))
        .collect()
}

/// GPU time of a frame from two timestamps (wall and host time: [`crate::FrameClock`]), and
/// optionally of its parts, split at marks between them ([`FrameTimer::with_marks`]). The
/// timestamps are resolved and copied into a mappable buffer by the frame's own last command
/// buffer ([`FrameTimer::end`]), so reading them ([`FrameTimer::gpu_ms`]) is one map: no
/// further submission and no buffer created per frame.
pub struct FrameTimer {
    query_set: Option<wgpu::QuerySet>,
    resolve: Option<wgpu::Buffer>,
    readback: Option<wgpu::Buffer>,
    period_ns: f32,
    /// Timestamps: begin, the marks, end.
    count: u32,
}

impl FrameTimer {
    pub fn new(gpu: &Gpu) -> FrameTimer {
        FrameTimer::with_marks(gpu, 0)
    }

    /// A timer whose frame is split into `marks + 1` intervals by `marks` timestamps written
    /// with [`FrameTimer::mark`] (each of them every frame, in order, between begin and end).
    pub fn with_marks(gpu: &Gpu, marks: u32) -> FrameTimer {
        let count = marks + 2;
        let bytes = count as u64 * 8;
        let (query_set, resolve, readback) = if gpu.has_timestamps() {
            let qs = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("frame timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count,
            });
            let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let readback = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp readback"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            (Some(qs), Some(buf), Some(readback))
        } else {
            (None, None, None)
        };
        FrameTimer {
            query_set,
            resolve,
            readback,
            period_ns: gpu.queue.get_timestamp_period(),
            count,
        }
    }

    /// Writes the "begin" timestamp into `encoder` (first command of the frame's GPU work).
    pub fn begin(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(qs) = &self.query_set {
            encoder.write_timestamp(qs, 0);
        }
    }

    /// Writes mark `i` (0-based, below the `marks` of [`FrameTimer::with_marks`]): the end of
    /// interval `i` and the start of interval `i + 1`.
    pub fn mark(&self, encoder: &mut wgpu::CommandEncoder, i: u32) {
        assert!(
            i + 2 < self.count,
            "FrameTimer: mark {i} of {}",
            self.count - 2
        );
        if let Some(qs) = &self.query_set {
            encoder.write_timestamp(qs, i + 1);
        }
    }

    /// Writes the "end" timestamp, resolves them all and copies them where
    /// [`FrameTimer::gpu_ms`] maps them (last commands of the frame's GPU work).
    pub fn end(&self, encoder: &mut wgpu::CommandEncoder) {
        if let (Some(qs), Some(buf), Some(readback)) =
            (&self.query_set, &self.resolve, &self.readback)
        {
            encoder.write_timestamp(qs, self.count - 1);
            encoder.resolve_query_set(qs, 0..self.count, buf, 0);
            encoder.copy_buffer_to_buffer(buf, 0, readback, 0, self.count as u64 * 8);
        }
    }

    /// GPU milliseconds between begin and end (after the work was submitted; blocks).
    pub fn gpu_ms(&self, gpu: &Gpu) -> anyhow::Result<Option<f64>> {
        Ok(self.gpu_intervals_ms(gpu)?.map(|v| v.iter().sum()))
    }

    /// GPU milliseconds of each interval, begin to the first mark, …, the last mark to end
    /// (after the work was submitted; blocks). Their sum is [`FrameTimer::gpu_ms`].
    pub fn gpu_intervals_ms(&self, gpu: &Gpu) -> anyhow::Result<Option<Vec<f64>>> {
        let Some(readback) = &self.readback else {
            return Ok(None);
        };
        let bytes = gpu.map_and_copy(readback, self.count as u64 * 8, &mut Duration::default())?;
        let t: &[u64] = bytemuck::cast_slice(&bytes);
        let ms = self.period_ns as f64 * 1e-6;
        Ok(Some(
            t.windows(2)
                .map(|w| w[1].saturating_sub(w[0]) as f64 * ms)
                .collect(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The environment's device request: unset is the adapter as it is; a wrong value is an
    /// error naming the variable.
    #[test]
    fn device_request_from_variables() {
        let vars = |pairs: &'static [(&'static str, &'static str)]| {
            move |k: &str| {
                pairs
                    .iter()
                    .find(|(n, _)| *n == k)
                    .map(|(_, v)| v.to_string())
            }
        };
        assert_eq!(
            DeviceRequest::from_vars(vars(&[])).unwrap(),
            DeviceRequest::default()
        );
        assert_eq!(
            DeviceRequest::from_vars(vars(&[
                (ENV_MAX_STORAGE_BINDING, "262144"),
                (ENV_TIMESTAMPS, "off")
            ]))
            .unwrap(),
            DeviceRequest {
                max_storage_binding: Some(262144),
                no_timestamps: true,
                max_triangles_per_pass: None,
            }
        );
        let e = DeviceRequest::from_vars(vars(&[(ENV_MAX_STORAGE_BINDING, "4k")]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("TETBENCH_MAX_STORAGE_BINDING=\"4k\""), "{e}");
        let e = DeviceRequest::from_vars(vars(&[(ENV_TIMESTAMPS, "no")]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("TETBENCH_TIMESTAMPS") && e.contains("on or off"),
            "{e}"
        );
    }

    #[test]
    fn chunks_cover_everything_once() {
        let r = chunk_ranges(1000, 16, 16 * 300);
        assert_eq!(r, vec![0..300, 300..600, 600..900, 900..1000]);
        assert_eq!(chunk_ranges(5, 16, 1 << 27), vec![0..5]);
    }
}

#[cfg(test)]
mod device_tests {
    use super::*;

    /// An allocation past the adapter's limits fails with the figures, before wgpu sees it.
    #[test]
    fn oversized_buffers_and_textures_are_refused_with_the_limit() {
        let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
        let mut ledger = MemoryLedger::default();
        let max = gpu.limits.max_buffer_size;
        let too_big = (max + 4).div_ceil(4) * 4;
        let e = ledger
            .buffer(
                &gpu,
                "k-buffer",
                Lifetime::PerFrame,
                too_big,
                wgpu::BufferUsages::STORAGE,
            )
            .unwrap_err()
            .to_string();
        assert!(e.contains(&format!("needs {too_big} bytes")), "{e}");
        assert!(e.contains("\"k-buffer\""), "{e}");
        assert!(e.contains(&format!("allows {max} bytes")), "{e}");
        assert_eq!(ledger.total(), 0, "nothing was allocated");
        let side = gpu.limits.max_texture_dimension_2d + 1;
        let e = ledger
            .texture(
                &gpu,
                Lifetime::PerFrame,
                &wgpu::TextureDescriptor {
                    label: Some("target"),
                    size: wgpu::Extent3d {
                        width: side,
                        height: 8,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wgpu::TextureFormat::Rgba32Float,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                    view_formats: &[],
                },
            )
            .unwrap_err()
            .to_string();
        assert!(e.contains("max_texture_dimension_2d"), "{e}");
    }

    /// The headless device opens (lavapipe on machines without a GPU) and round-trips data.
    #[test]
    fn device_opens_and_reads_back() {
        let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
        let mut ledger = MemoryLedger::default();
        let data: Vec<u32> = (0..1000).collect();
        let buf = ledger
            .buffer_init(
                &gpu,
                "test",
                Lifetime::Persistent,
                bytemuck::cast_slice(&data),
                wgpu::BufferUsages::COPY_SRC,
            )
            .unwrap();
        let back = gpu.read_buffer(&buf, 0, 4000).unwrap();
        assert_eq!(bytemuck::cast_slice::<u8, u32>(&back), &data[..]);
        assert_eq!(ledger.persistent, 4000);
        assert!(!gpu.adapter.name.is_empty());
        eprintln!(
            "adapter: {:?}, timestamps: {}, limits: {:?}",
            gpu.adapter,
            gpu.has_timestamps(),
            gpu.limits
        );
    }

    /// Readbacks reuse their mappable buffers (none created per frame) and still
    /// return exactly the bytes asked for: a smaller read after a larger one, an offset read,
    /// and a larger one that needs a new buffer.
    #[test]
    fn readbacks_reuse_their_buffers_and_return_the_same_bytes() {
        let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
        let mut ledger = MemoryLedger::default();
        let data: Vec<u32> = (0..4096).map(|i| i * 7 + 1).collect();
        let buf = ledger
            .buffer_init(
                &gpu,
                "test",
                Lifetime::Persistent,
                bytemuck::cast_slice(&data),
                wgpu::BufferUsages::COPY_SRC,
            )
            .unwrap();
        let created = gpu.staging_buffers_created();
        let read = |offset: u64, size: u64| -> Vec<u32> {
            bytemuck::cast_slice(&gpu.read_buffer(&buf, offset, size).unwrap()).to_vec()
        };
        assert_eq!(read(0, 4000), &data[..1000]);
        assert_eq!(read(0, 32), &data[..8]);
        assert_eq!(read(400, 64), &data[100..116]);
        assert_eq!(
            gpu.staging_buffers_created() - created,
            1,
            "one 4 KiB buffer serves all three"
        );
        assert_eq!(read(0, 16384), &data[..]);
        assert_eq!(gpu.staging_buffers_created() - created, 2);
        for _ in 0..10 {
            assert_eq!(read(4, 8), &data[1..3]);
        }
        assert_eq!(gpu.staging_buffers_created() - created, 2);
        // The frame timer maps its own buffer: no readback buffer per frame either.
        let timer = FrameTimer::new(&gpu);
        for _ in 0..3 {
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            timer.begin(&mut enc);
            timer.end(&mut enc);
            gpu.queue.submit([enc.finish()]);
            gpu.wait().unwrap();
            let ms = timer.gpu_ms(&gpu).unwrap();
            assert_eq!(ms.is_some(), gpu.has_timestamps());
            assert!(ms.is_none_or(|m| m >= 0.0));
        }
        assert_eq!(gpu.staging_buffers_created() - created, 2);
    }
}
