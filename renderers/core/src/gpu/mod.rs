//! The headless wgpu context every GPU algorithm shares, GPU timing by timestamp queries, memory
//! accounting, readback, and splitting of large arrays across storage bindings.
//!
//! Runs on any backend: Vulkan through Mesa's lavapipe where there is no GPU (CI, developers'
//! machines), Vulkan/Metal/DX12 on real hardware. Every result row records which.
//!
//! `request.rs` what to ask of the adapter, `pipelines.rs` the shader and pipeline builders,
//! `layouts.rs` bind-group layouts from typed bindings, bind groups and pipeline layouts,
//! `readback.rs` copies to the host through kept mappable buffers, `memory.rs` the ledger and
//! chunking, `timer.rs` the timestamp queries.

mod layouts;
mod memory;
mod pipelines;
mod readback;
mod request;
mod timer;

use anyhow::{anyhow, Context};
use serde::{Deserialize, Serialize};

pub use layouts::{BindingNumbers, LayoutEntries};
pub use memory::{chunk_ranges, Lifetime, MemoryLedger, UPLOAD_CHUNK};
pub use pipelines::RasterState;
pub use request::{
    DeviceRequest, ENV_MAX_STORAGE_BINDING, ENV_MAX_TRIANGLES_PER_PASS, ENV_TIMESTAMPS,
};
pub use timer::FrameTimer;

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
}

/// Triangles per render pass when a whole mesh is drawn. Lavapipe bins every triangle of a
/// pass before it rasterises the pass's tiles, and shades and bins a draw's vertices whole, so
/// one pass or one draw over a large mesh holds host memory in proportion to it. Measured on
/// `box:2m` at 512² (resident peak of the run): HAVS's 4 M faces in one draw 1.68 GB, in draws
/// of 262,144 triangles 0.80 GB; GATOR (draws of 1,024 tets already) in one pass 0.95 GB, in
/// passes of 262,144 tets 0.57 GB, frame times within their spread (docs/profile.md).
/// `crate::bind::pass_slices` cuts a mesh's vertices into such passes.
pub const MAX_TRIANGLES_PER_PASS: u32 = 1 << 20;

#[cfg(test)]
mod device_tests;
