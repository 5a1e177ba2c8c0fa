//! Phases 1–2 of the frame (§2.4, §3.2): the first hit, then one peeling layer per pass.

use std::time::Instant;

use render_core::{FrameClock, Gpu};

use super::State;
use crate::resources::Target;
use crate::settings::RaycastSettings;

/// What the peel found: the layers in use, the draws it took (each rasterises every boundary
/// face), and whether the spare slot was drawn to count the re-entries that are dropped.
pub(super) struct Peeled {
    pub layers: u32,
    pub draws: u32,
    pub dropped_check: bool,
}

/// Phases 1–2 into `t`'s layer slots (`slots` = the maximum layers + the spare).
pub(super) fn peel(
    gpu: &Gpu,
    st: &State,
    t: &Target,
    s: &RaycastSettings,
    slots: u32,
    clock: &mut FrameClock,
) -> anyhow::Result<Peeled> {
    // Phases 1–2: peel until a layer is empty (occlusion query) or the maximum is reached; then
    // one more layer into the spare slot, only to count the re-entries that are dropped. With a
    // stencil, a layer after which no pixel had a second candidate ends the peel without the
    // empty pass that would show it (`Pipelines::more`): the same layers, one draw fewer.
    let (mut layers_used, mut peel_draws, mut dropped_check) = (0u32, 0u32, false);
    let t_peel = Instant::now();
    for l in 0..slots {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        if l == 0 {
            st.timer.begin(&mut enc);
        }
        let queries = encode_layer(&mut enc, st, t, l);
        clock.submit(gpu, [enc.finish()]);
        peel_draws += 1;
        let q = clock.read_buffer(
            gpu,
            &t.occlusion_resolve,
            l as u64 * wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT,
            8 * queries as u64,
        )?;
        let count = |i: usize| u64::from_le_bytes(q[8 * i..8 * i + 8].try_into().expect("8 bytes"));
        if count(0) == 0 {
            break;
        }
        if l == s.max_layers {
            dropped_check = true;
            break;
        }
        layers_used += 1;
        if queries == 2 && count(1) == 0 {
            break;
        }
    }
    clock.stage("peel", t_peel);
    Ok(Peeled {
        layers: layers_used,
        draws: peel_draws,
        dropped_check,
    })
}

/// Layer `l`'s pass: clear its slot and the depth (and stencil), draw the front-facing boundary
/// faces under occlusion query 2l, with a stencil the full-screen test under query 2l + 1, and
/// resolve them. Returns how many queries were resolved (1 or 2).
fn encode_layer(enc: &mut wgpu::CommandEncoder, st: &State, t: &Target, l: u32) -> u32 {
    {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("raycast peel"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &t.layer_views[l as usize],
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: u32::MAX as f64,
                        g: u32::MAX as f64,
                        b: u32::MAX as f64,
                        a: u32::MAX as f64,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &t.depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: st.pipes.more.as_ref().map(|_| wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0),
                    store: wgpu::StoreOp::Discard,
                }),
            }),
            timestamp_writes: None,
            occlusion_query_set: Some(&t.occlusion),
            multiview_mask: None,
        });
        if l == 0 {
            pass.set_pipeline(&st.pipes.first);
        } else {
            pass.set_pipeline(&st.pipes.peel);
            pass.set_bind_group(1, &t.peel_binds[l as usize - 1], &[]);
        }
        pass.set_bind_group(0, &st.mesh_bind, &[]);
        pass.set_bind_group(2, &st.peel_frame_bind, &[]);
        pass.set_vertex_buffer(0, st.faces.slice(..));
        // The candidates' count tests 0 ≤ stencil (`COUNT_CANDIDATES`).
        pass.set_stencil_reference(0);
        pass.begin_occlusion_query(2 * l);
        pass.draw(0..st.face_vertices, 0..1);
        pass.end_occlusion_query();
        if let Some(more) = &st.pipes.more {
            pass.set_pipeline(more);
            pass.set_stencil_reference(1);
            pass.begin_occlusion_query(2 * l + 1);
            pass.draw(0..3, 0..1);
            pass.end_occlusion_query();
        }
    }
    let queries = if st.pipes.more.is_some() { 2 } else { 1 };
    enc.resolve_query_set(
        &t.occlusion,
        2 * l..2 * l + queries,
        &t.occlusion_resolve,
        l as u64 * wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT,
    );
    queries
}
