//! Pipelines, bind group layouts and the per-frame parameters of the splatter.

use render_core::bind;
use render_core::gpu::LayoutEntries;
use render_core::table_texture::TableTexture;
use render_core::Gpu;

/// Must match `Frame` in `frame.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameParams {
    pub view_proj: [[f32; 4]; 4],
    pub depth_row: [f32; 4],
    pub viewport: [f32; 2],
    pub tan_half: [f32; 2],
    pub focal_px: f32,
    pub perspective: u32,
    pub d0: f32,
    pub inv_delta: f32,
    pub delta_world: f32,
    pub num_slabs: u32,
    pub n: u32,
    pub padded: u32,
    pub radius_slabs: u32,
    pub subslices: u32,
    pub footprint: u32,
    pub tf_entries: u32,
    pub kernel_radius: f32,
    pub kernel_unit: f32,
    pub density_scale: f32,
    pub ese_alpha: f32,
    pub kernel_radius_world: f32,
    pub length_unit: f32,
    pub pad: [f32; 2],
}

/// Must match `Slab` in `frame.wgsl` (read by `splat.wgsl` and `composite.wgsl`): one step
/// of a brick, at a dynamic offset per step — add the sorted voxels `first .. first + count`
/// to the sheets of slabs `first_slab ..= last_slab`, then composite ring slot `slot`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SlabParams {
    pub first: u32,
    pub count: u32,
    pub first_slab: u32,
    pub last_slab: u32,
    pub slot: u32,
    /// Invocations per voxel: each takes every `lanes`-th row of the voxel's footprint.
    pub lanes: u32,
    pub pad1: u32,
    pub pad2: u32,
}

/// The `#[repr(C)]` structs this crate uploads to the GPU and the WGSL structs they mirror,
/// for the layout test (`tests/gpu_layouts.rs`, through [`crate::DESCRIPTION`]).
#[doc(hidden)]
pub fn gpu_layouts() -> render_core::gpu_layout::GpuLayouts {
    let structs = vec![
        render_core::rust_layout!(FrameParams => "frame.wgsl::Frame" {
            view_proj, depth_row, viewport, tan_half, focal_px, perspective, d0, inv_delta,
            delta_world, num_slabs, n, padded, radius_slabs, subslices, footprint, tf_entries,
            kernel_radius, kernel_unit, density_scale, ese_alpha, kernel_radius_world,
            length_unit, pad
        }),
        render_core::rust_layout!(SlabParams => "frame.wgsl::Slab" {
            first, count, first_slab, last_slab, slot, lanes, pad1, pad2
        }),
    ];
    render_core::gpu_layout::GpuLayouts {
        structs,
        sources: vec![
            ("frame.wgsl", include_str!("frame.wgsl").into()),
            ("splat.wgsl", include_str!("splat.wgsl").into()),
        ],
    }
}

pub const IMAGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

pub struct Pipelines {
    pub compute_layout: wgpu::BindGroupLayout,
    pub transform: wgpu::ComputePipeline,
    pub gather: wgpu::ComputePipeline,
    pub boundaries: wgpu::ComputePipeline,
    pub bitonic_layout: wgpu::BindGroupLayout,
    pub bitonic_double: wgpu::ComputePipeline,
    pub bitonic_wide: wgpu::ComputePipeline,
    pub bitonic_narrow: wgpu::ComputePipeline,
    pub splat_layout: wgpu::BindGroupLayout,
    pub slab_layout: wgpu::BindGroupLayout,
    pub splat: wgpu::ComputePipeline,
    pub composite_layout: wgpu::BindGroupLayout,
    pub composite: wgpu::RenderPipeline,
}

fn with_frame(body: &str) -> String {
    format!("{}\n{}", include_str!("frame.wgsl"), body)
}

impl Pipelines {
    /// Every parameter block (frame, step, bitonic stage) is bound with
    /// [`bind::params_entry`]: a uniform buffer set again before every dispatch made lavapipe's
    /// memory grow with every frame. The images are bit for bit the same.
    /// `filtered`: the footprint table is sampled with trilinear filtering (`splat.wgsl`,
    /// TABLE_FILTERED) rather than loaded and interpolated by hand.
    pub fn new(gpu: &Gpu, filtered: bool) -> Pipelines {
        let c = wgpu::ShaderStages::COMPUTE;
        let compute_layout = LayoutEntries::new(c)
            .params(0)
            .read(1)
            .read_write(2..=5)
            .build(gpu, "splat buckets");
        let compute_module = gpu.shader(
            "splat compute.wgsl",
            &with_frame(include_str!("compute.wgsl")),
        );
        let [transform, gather, boundaries] = gpu.compute_pipelines(
            "splat",
            &[&compute_layout],
            &compute_module,
            ["transform", "gather", "boundaries"],
        );

        let bitonic_layout = LayoutEntries::new(c)
            .params_at_offset(0)
            .read_write(1..=2)
            .build(gpu, "splat bitonic");
        let bitonic_module = gpu.shader("splat bitonic.wgsl", include_str!("bitonic.wgsl"));
        let [bitonic_double, bitonic_wide, bitonic_narrow] = gpu.compute_pipelines(
            "splat",
            &[&bitonic_layout],
            &bitonic_module,
            ["bitonic_double", "bitonic_wide", "bitonic_narrow"],
        );

        let splat_layout = LayoutEntries::new(c)
            .params(0)
            .read(1)
            // The footprint slices (binding 2) and their sampler (6), a 3D table texture's entries.
            .with(TableTexture::layout_entries(filtered, 2, 6, c))
            .texture(3, wgpu::TextureViewDimension::D2)
            // Fragments dropped by early splat elimination (counted, not timed).
            .read_write(4..=5)
            .build(gpu, "splat sheet");
        // The step: the splat pass reads its bucket, the composite its ring slot.
        let slab_layout = LayoutEntries::new(c | wgpu::ShaderStages::FRAGMENT)
            .params_at_offset(0)
            .build(gpu, "splat slab");
        let splat_source = format!(
            "const SPLAT_WORKGROUP: u32 = {SPLAT_WORKGROUP}u;\nconst TABLE_FILTERED: bool = {filtered};\n{}",
            with_frame(include_str!("splat.wgsl"))
        );
        let splat_module = gpu.shader("splat splat.wgsl", &splat_source);
        let [splat] = gpu.compute_pipelines(
            "splat sheet",
            &[&splat_layout, &slab_layout],
            &splat_module,
            ["splat_cs"],
        );

        let composite_layout = LayoutEntries::new(wgpu::ShaderStages::FRAGMENT)
            .params(0)
            .read_write(1)
            .read(2)
            .build(gpu, "splat composite");
        let composite = composite_pipeline(gpu, &composite_layout, &slab_layout);
        Pipelines {
            compute_layout,
            transform,
            gather,
            boundaries,
            bitonic_layout,
            bitonic_double,
            bitonic_wide,
            bitonic_narrow,
            splat_layout,
            slab_layout,
            splat,
            composite_layout,
            composite,
        }
    }
}

/// The composite pass: a full-screen triangle blending a slab's sheet "under" the image.
fn composite_pipeline(
    gpu: &Gpu,
    composite_layout: &wgpu::BindGroupLayout,
    slab_layout: &wgpu::BindGroupLayout,
) -> wgpu::RenderPipeline {
    let composite_module = gpu.shader(
        "splat composite.wgsl",
        &format!(
            "{}\n{}",
            with_frame(include_str!("composite.wgsl")),
            bind::FULLSCREEN_WGSL
        ),
    );
    // Front-to-back "under": C += (1 − A_dst) · C_src, premultiplied.
    let under = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::OneMinusDstAlpha,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    };
    gpu.triangle_pipeline(
        "splat composite",
        &gpu.pipeline_layout("splat composite", &[composite_layout, slab_layout]),
        &composite_module,
        "fullscreen_vs",
        "composite_fs",
        IMAGE_FORMAT,
        Some(wgpu::BlendState {
            color: under,
            alpha: under,
        }),
        wgpu::ColorWrites::ALL,
    )
}

/// Workgroups (x, y) for `threads` threads of 256, split over two dimensions past the
/// per-dimension limit (shaders rebuild the flat id).
pub fn workgroups(threads: u32) -> (u32, u32) {
    workgroups_of(threads, 256)
}

/// Invocations in one workgroup of the splat pass (`splat_cs`, given to the shader as
/// `SPLAT_WORKGROUP`). A bucket holds a few hundred voxels, so a dispatch is a handful of
/// workgroups, and a software rasteriser runs each workgroup on one thread: at 256, a bucket of
/// 300 voxels left one of lavapipe's two threads idle for five sixths of its dispatch (box:10k
/// and shell:10k at 128² from diagonal views, docs/roofline.md). 64 keeps whole warps and
/// wavefronts on a GPU.
pub const SPLAT_WORKGROUP: u32 = 64;

/// Workgroups (x, y) for `threads` threads of `size`, split like [`workgroups`].
pub fn workgroups_of(threads: u32, size: u32) -> (u32, u32) {
    let wg = threads.div_ceil(size).max(1);
    let x = wg.min(32_768);
    (x, wg.div_ceil(x))
}

/// One dispatch of the bitonic sort (bitonic.wgsl), four compare-exchanges per invocation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BitonicStep {
    /// Stages (k, j) and (k, j / 2), j ≥ 8 (`bitonic_double`).
    Double { k: u32, j: u32 },
    /// Stage (k, j), j ≥ 4 (`bitonic_wide`).
    Wide { k: u32, j: u32 },
    /// Stages (k, 2) and (k, 1), or (2, 1) alone (`bitonic_narrow`).
    Narrow { k: u32 },
}

impl BitonicStep {
    /// The `Stage` block (k, j, n, 0); a narrow step's j is 0.
    pub fn params(self, n: u32) -> [u32; 4] {
        match self {
            BitonicStep::Double { k, j } | BitonicStep::Wide { k, j } => [k, j, n, 0],
            BitonicStep::Narrow { k } => [k, 0, n, 0],
        }
    }

    /// Invocations of the step over `n` elements.
    pub fn invocations(self, n: u32) -> u32 {
        match self {
            BitonicStep::Double { .. } => n / 16,
            BitonicStep::Wide { .. } => n / 8,
            BitonicStep::Narrow { .. } => n / 4,
        }
    }
}

/// The dispatches of a bitonic sort of `n` (a power of two, ≥ 4) elements: the network's
/// stages (`bitonic_stages` in the tests) in its order, (k, 2) and (k, 1) in one dispatch.
pub fn bitonic_steps(n: u32) -> Vec<BitonicStep> {
    let mut out = vec![];
    let mut k = 2;
    while k <= n {
        let mut j = k / 2;
        while j >= 4 {
            if j >= 8 {
                out.push(BitonicStep::Double { k, j });
                j /= 4;
            } else {
                out.push(BitonicStep::Wide { k, j });
                j /= 2;
            }
        }
        out.push(BitonicStep::Narrow { k });
        k *= 2;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The (k, j) stages of a bitonic network over `n` (a power of two) elements.
    fn bitonic_stages(n: u32) -> Vec<(u32, u32)> {
        let mut out = vec![];
        let mut k = 2;
        while k <= n {
            let mut j = k / 2;
            while j > 0 {
                out.push((k, j));
                j /= 2;
            }
            k *= 2;
        }
        out
    }

    /// The (k, j) stages a list of steps performs, in order.
    fn expand(steps: &[BitonicStep]) -> Vec<(u32, u32)> {
        let mut out = vec![];
        for &step in steps {
            match step {
                BitonicStep::Double { k, j } => out.extend([(k, j), (k, j / 2)]),
                BitonicStep::Wide { k, j } => out.push((k, j)),
                BitonicStep::Narrow { k } => {
                    if k >= 4 {
                        out.push((k, 2));
                    }
                    out.push((k, 1));
                }
            }
        }
        out
    }

    #[test]
    fn the_steps_perform_the_networks_stages_in_its_order() {
        for shift in 2..=24 {
            let n = 1u32 << shift;
            assert_eq!(expand(&bitonic_steps(n)), bitonic_stages(n), "n = {n}");
        }
        // A wrong step list is caught: the narrow step without its (k, 2) stage.
        let mut wrong = expand(&bitonic_steps(64));
        wrong.retain(|&(k, j)| !(k == 8 && j == 2));
        assert_ne!(wrong, bitonic_stages(64));
    }
}
