//! The shader and pipeline builders every algorithm's setup goes through.

use super::Gpu;

impl Gpu {
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

    /// A render pipeline of `layout` whose vertex and fragment stages both come from `module`,
    /// drawn as `state` says (one sample, no multiview, no pipeline cache).
    pub fn render_pipeline(
        &self,
        label: &str,
        layout: &wgpu::PipelineLayout,
        module: &wgpu::ShaderModule,
        state: RasterState<'_>,
    ) -> wgpu::RenderPipeline {
        self.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some(state.vertex_entry),
                    compilation_options: Default::default(),
                    buffers: state.vertex_buffers,
                },
                primitive: state.primitive,
                depth_stencil: state.depth_stencil,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module,
                    entry_point: Some(state.fragment_entry),
                    compilation_options: Default::default(),
                    targets: state.targets,
                }),
                multiview_mask: None,
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
        let state = RasterState {
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend,
                write_mask,
            })],
            ..RasterState::new(vertex_entry, fragment_entry)
        };
        self.render_pipeline(label, layout, module, state)
    }
}

/// What a render pipeline of [`Gpu::render_pipeline`] draws with: its entry points, vertex
/// buffers, primitive, depth and stencil, and colour targets.
#[derive(Debug, Clone)]
pub struct RasterState<'a> {
    pub vertex_entry: &'a str,
    pub fragment_entry: &'a str,
    pub vertex_buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    pub primitive: wgpu::PrimitiveState,
    pub depth_stencil: Option<wgpu::DepthStencilState>,
    pub targets: &'a [Option<wgpu::ColorTargetState>],
}

impl<'a> RasterState<'a> {
    /// `vertex_entry` and `fragment_entry` drawing a triangle list from both sides, with no
    /// vertex buffers, no depth or stencil and no colour target: fields to override.
    pub fn new(vertex_entry: &'a str, fragment_entry: &'a str) -> Self {
        RasterState {
            vertex_entry,
            fragment_entry,
            vertex_buffers: &[],
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: None,
            targets: &[],
        }
    }

    /// The same with a depth test of `compare` against a `format` attachment, writing the
    /// depth when `write` (no stencil, no bias).
    pub fn depth_test(
        self,
        format: wgpu::TextureFormat,
        compare: wgpu::CompareFunction,
        write: bool,
    ) -> Self {
        RasterState {
            depth_stencil: Some(wgpu::DepthStencilState {
                format,
                depth_write_enabled: Some(write),
                depth_compare: Some(compare),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            ..self
        }
    }

    /// The same with `stencil` on its depth attachment (after [`RasterState::depth_test`]).
    pub fn stencil(mut self, stencil: wgpu::StencilState) -> Self {
        debug_assert!(
            self.depth_stencil.is_some(),
            "a stencil needs a depth attachment"
        );
        if let Some(ds) = &mut self.depth_stencil {
            ds.stencil = stencil;
        }
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The state starts as the cell projections draw (a triangle list from both sides, nothing
    /// else); a depth test and a stencil land on the one depth attachment, and a stencil is
    /// all that differs between two states built the same way otherwise.
    #[test]
    fn raster_state_builds_the_depth_attachment_it_is_given() {
        let plain = RasterState::new("vs", "fs");
        assert_eq!(
            plain.primitive.topology,
            wgpu::PrimitiveTopology::TriangleList
        );
        assert_eq!(plain.primitive.cull_mode, None);
        assert!(plain.depth_stencil.is_none() && plain.targets.is_empty());
        let format = wgpu::TextureFormat::Depth32FloatStencil8;
        let depth = plain.depth_test(format, wgpu::CompareFunction::Less, true);
        let ds = depth.depth_stencil.clone().expect("a depth attachment");
        assert_eq!(
            (ds.format, ds.depth_write_enabled, ds.depth_compare),
            (format, Some(true), Some(wgpu::CompareFunction::Less))
        );
        assert!(!ds.stencil.is_enabled());
        let face = wgpu::StencilFaceState {
            compare: wgpu::CompareFunction::Less,
            ..Default::default()
        };
        let stencil = wgpu::StencilState {
            front: face,
            back: face,
            read_mask: 0xff,
            write_mask: 0,
        };
        let stencilled = depth.stencil(stencil.clone());
        let with = stencilled.depth_stencil.expect("a depth attachment");
        assert_eq!(with.stencil, stencil);
        assert_eq!(
            wgpu::DepthStencilState {
                stencil: ds.stencil.clone(),
                ..with
            },
            ds
        );
    }
}
