//! Bind-group layouts from typed bindings, and the bind groups and pipeline layouts built on
//! them: what every algorithm's setup spelled out as wgpu descriptors.
//!
//! A layout is a list of bindings, each a number and what the shader declares there (a
//! uniform block, a parameter block, a read-only or read-write storage array, a texture), seen
//! by the stages in force when it was added:
//!
//! ```ignore
//! let layout = LayoutEntries::new(wgpu::ShaderStages::COMPUTE)
//!     .params(0)
//!     .read(1)
//!     .read_write(2..=5)
//!     .build(gpu, "splat buckets");
//! ```

use super::Gpu;
use crate::bind;

/// Binding numbers: one (`3`) or a run (`2..6`, `2..=5`).
pub trait BindingNumbers {
    fn numbers(self) -> std::ops::Range<u32>;
}

impl BindingNumbers for u32 {
    fn numbers(self) -> std::ops::Range<u32> {
        self..self + 1
    }
}

impl BindingNumbers for std::ops::Range<u32> {
    fn numbers(self) -> std::ops::Range<u32> {
        self
    }
}

impl BindingNumbers for std::ops::RangeInclusive<u32> {
    fn numbers(self) -> std::ops::Range<u32> {
        *self.start()..*self.end() + 1
    }
}

/// The entries of a bind-group layout, added binding by binding with the visibility in force.
#[derive(Debug, Clone)]
pub struct LayoutEntries {
    visibility: wgpu::ShaderStages,
    entries: Vec<wgpu::BindGroupLayoutEntry>,
}

impl LayoutEntries {
    /// No entries yet; the ones added next are seen by `visibility`.
    pub fn new(visibility: wgpu::ShaderStages) -> LayoutEntries {
        LayoutEntries {
            visibility,
            entries: Vec::new(),
        }
    }

    /// The entries added after this are seen by `visibility`.
    pub fn visible(mut self, visibility: wgpu::ShaderStages) -> Self {
        self.visibility = visibility;
        self
    }

    fn each(
        mut self,
        bindings: impl BindingNumbers,
        entry: impl Fn(u32, wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry,
    ) -> Self {
        let v = self.visibility;
        self.entries.extend(bindings.numbers().map(|b| entry(b, v)));
        self
    }

    /// A uniform block.
    pub fn uniform(self, bindings: impl BindingNumbers) -> Self {
        self.each(bindings, bind::uniform_entry)
    }

    /// A parameter block that a pass binds again ([`bind::params_entry`] says why it is a
    /// read-only storage buffer).
    pub fn params(self, bindings: impl BindingNumbers) -> Self {
        self.each(bindings, bind::params_entry)
    }

    /// A parameter block bound at a dynamic offset (one entry of several per buffer).
    pub fn params_at_offset(self, bindings: impl BindingNumbers) -> Self {
        self.each(bindings, |b, v| {
            bind::with_dynamic_offset(bind::params_entry(b, v))
        })
    }

    /// A read-only storage array.
    pub fn read(self, bindings: impl BindingNumbers) -> Self {
        self.each(bindings, |b, v| bind::storage_entry(b, v, true))
    }

    /// A read-write storage array.
    pub fn read_write(self, bindings: impl BindingNumbers) -> Self {
        self.each(bindings, |b, v| bind::storage_entry(b, v, false))
    }

    /// A float texture of `dimension`, not filterable (read with `textureLoad`).
    pub fn texture(
        self,
        bindings: impl BindingNumbers,
        dimension: wgpu::TextureViewDimension,
    ) -> Self {
        self.each(bindings, |b, v| bind::texture_entry(b, v, false, dimension))
    }

    /// An unsigned-integer texture of `dimension` (records of texels read with `textureLoad`:
    /// [`crate::texel_texture`], a renderer's own `Rgba32Uint` targets).
    pub fn uint_texture(
        self,
        bindings: impl BindingNumbers,
        dimension: wgpu::TextureViewDimension,
    ) -> Self {
        self.each(bindings, |b, v| {
            bind::sampled_texture_entry(b, v, wgpu::TextureSampleType::Uint, dimension)
        })
    }

    /// Entries built elsewhere (a table texture and its sampler, a chunked array's buffers),
    /// with their own visibility.
    pub fn with(mut self, entries: impl IntoIterator<Item = wgpu::BindGroupLayoutEntry>) -> Self {
        self.entries.extend(entries);
        self
    }

    pub fn entries(&self) -> &[wgpu::BindGroupLayoutEntry] {
        &self.entries
    }

    /// The layout.
    pub fn build(&self, gpu: &Gpu, label: &str) -> wgpu::BindGroupLayout {
        gpu.device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &self.entries,
            })
    }
}

impl Gpu {
    /// A bind group of `entries` in `layout`.
    pub fn bind_group(
        &self,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        entries: &[wgpu::BindGroupEntry<'_>],
    ) -> wgpu::BindGroup {
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout,
            entries,
        })
    }

    /// A pipeline layout whose group `i` is `groups[i]`.
    pub fn pipeline_layout(
        &self,
        label: &str,
        groups: &[&wgpu::BindGroupLayout],
    ) -> wgpu::PipelineLayout {
        let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().map(|g| Some(*g)).collect();
        bind::pipeline_layout(self, label, &groups)
    }

    /// The compute pipelines of `entries` in `module`, all over the bind groups `groups`
    /// (one pipeline layout), labelled `LABEL ENTRY`.
    pub fn compute_pipelines<const N: usize>(
        &self,
        label: &str,
        groups: &[&wgpu::BindGroupLayout],
        module: &wgpu::ShaderModule,
        entries: [&str; N],
    ) -> [wgpu::ComputePipeline; N] {
        let layout = self.pipeline_layout(label, groups);
        entries.map(|entry| {
            self.compute_pipeline(&format!("{label} {entry}"), Some(&layout), module, entry)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use wgpu::ShaderStages as S;

    /// The builder gives the entries the single-entry functions give, in the order added, each
    /// with the visibility in force when it was added.
    #[test]
    fn typed_bindings_give_the_entries_of_the_entry_functions() {
        let built = LayoutEntries::new(S::COMPUTE)
            .params(0)
            .read(1)
            .read_write(2..=3)
            .visible(S::FRAGMENT)
            .uniform(4)
            .params_at_offset(5)
            .texture(6..7, wgpu::TextureViewDimension::D1)
            .uint_texture(8, wgpu::TextureViewDimension::D2Array)
            .with([bind::storage_entry(9, S::VERTEX, true)]);
        let expected = [
            bind::params_entry(0, S::COMPUTE),
            bind::storage_entry(1, S::COMPUTE, true),
            bind::storage_entry(2, S::COMPUTE, false),
            bind::storage_entry(3, S::COMPUTE, false),
            bind::uniform_entry(4, S::FRAGMENT),
            bind::with_dynamic_offset(bind::params_entry(5, S::FRAGMENT)),
            bind::texture_entry(6, S::FRAGMENT, false, wgpu::TextureViewDimension::D1),
            bind::sampled_texture_entry(
                8,
                S::FRAGMENT,
                wgpu::TextureSampleType::Uint,
                wgpu::TextureViewDimension::D2Array,
            ),
            bind::storage_entry(9, S::VERTEX, true),
        ];
        assert_eq!(built.entries(), &expected[..]);
        // One binding different (read-write where the shader reads) is a different layout.
        let wrong = LayoutEntries::new(S::COMPUTE).params(0).read_write(1);
        assert_ne!(wrong.entries(), &expected[..2]);
    }

    /// Pipelines built through the builders run their own entry points: two of one module,
    /// each writing its own word through one bind group.
    #[test]
    fn built_pipelines_run_their_entry_points() {
        let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let out = crate::MemoryLedger::default()
            .buffer(&gpu, "out", crate::Lifetime::PerFrame, 8, usage)
            .unwrap();
        let module = gpu.shader(
            "builders",
            "@group(0) @binding(1) var<storage, read_write> out: array<u32>;\n\
             @compute @workgroup_size(1) fn first() { out[0] = 7u; }\n\
             @compute @workgroup_size(1) fn second() { out[1] = 9u; }",
        );
        let layout = LayoutEntries::new(S::COMPUTE)
            .read_write(1)
            .build(&gpu, "b");
        let pipes = gpu.compute_pipelines("b", &[&layout], &module, ["second", "first"]);
        let group = gpu.bind_group("b", &layout, &[bind::whole(1, &out)]);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_bind_group(0, &group, &[]);
            // Only the first pipeline built ("second"): word 1 written, word 0 not.
            pass.set_pipeline(&pipes[0]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        gpu.queue.submit([enc.finish()]);
        let back = gpu.read_buffer(&out, 0, 8).unwrap();
        assert_eq!(bytemuck::cast_slice::<u8, u32>(&back), &[0, 9]);
    }
}
