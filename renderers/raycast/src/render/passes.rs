//! Phase 3 in mode=passes (§2.3): rounds of [`COUNT_EVERY`] passes of one ray step each over
//! the tiles that still have active rays; the last pass of a round counts them per tile (the
//! paper's occlusion query), and a tile at zero gets no more passes.

use render_core::{FrameClock, Gpu};

use super::{active_tiles, read_counts, State};
use crate::resources::{Target, TilePipelines};
use crate::COUNT_EVERY;

/// What the rounds did: their number, and the tile rectangles drawn (two triangles each) where
/// the passes are drawn rather than dispatched.
pub(super) struct Rounds {
    pub rounds: u32,
    pub rectangles: u64,
}

/// Runs the rounds from the per-tile counts of active rays `counts` (every tile that has any is
/// listed); adds each tile's passes to `tile_passes`.
pub(super) fn run_passes(
    gpu: &Gpu,
    st: &State,
    t: &Target,
    groups: [u32; 2],
    mut counts: Vec<u32>,
    tile_passes: &mut [u32],
    clock: &mut FrameClock,
) -> anyhow::Result<Rounds> {
    let ntiles = tile_passes.len();
    let mut rounds = Rounds {
        rounds: 0,
        rectangles: 0,
    };
    let tiled = st.pipes.tile_passes.as_ref().zip(t.zcull.as_ref());
    loop {
        let active = active_tiles(&counts);
        if active.is_empty() {
            break;
        }
        gpu.queue
            .write_buffer(&t.active_tiles, 0, bytemuck::cast_slice(&active));
        gpu.queue
            .write_buffer(&t.tile_counts, 0, &[0u8; crate::resources::MAX_TILES * 4]);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        match tiled {
            Some((pipes, zcull)) => {
                encode_tile_round(
                    &mut enc,
                    st,
                    t,
                    pipes,
                    zcull,
                    active.len() as u32,
                    rounds.rounds == 0,
                );
                rounds.rectangles += active.len() as u64 * (COUNT_EVERY as u64 + 1);
            }
            None => {
                let mut pass = enc.begin_compute_pass(&Default::default());
                pass.set_pipeline(&st.pipes.step);
                pass.set_bind_group(0, &st.mesh_bind, &[]);
                for k in 0..COUNT_EVERY {
                    let count = (k + 1 == COUNT_EVERY) as usize;
                    pass.set_bind_group(1, &t.cast_binds[count], &[]);
                    pass.dispatch_workgroups(groups[0], groups[1], active.len() as u32);
                }
            }
        }
        clock.submit(gpu, [enc.finish()]);
        for &tile in &active {
            tile_passes[tile as usize] += COUNT_EVERY;
        }
        rounds.rounds += 1;
        counts = read_counts(gpu, clock, &t.tile_counts, ntiles)?;
    }
    Ok(rounds)
}

/// One round as the paper draws it: the depth update (ended rays to depth 0; the first round
/// clears the depth first), then [`COUNT_EVERY`] passes of a rectangle per active tile, each
/// its own render pass so that a pass sees the rays the one before it stored.
fn encode_tile_round(
    enc: &mut wgpu::CommandEncoder,
    st: &State,
    t: &Target,
    pipes: &TilePipelines,
    zcull: &wgpu::TextureView,
    tiles: u32,
    first: bool,
) {
    for k in 0..=COUNT_EVERY {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("raycast tile pass"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: zcull,
                depth_ops: Some(wgpu::Operations {
                    load: if first && k == 0 {
                        wgpu::LoadOp::Clear(1.0)
                    } else {
                        wgpu::LoadOp::Load
                    },
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(if k == 0 { &pipes.cull } else { &pipes.step });
        pass.set_bind_group(0, &st.mesh_bind, &[]);
        pass.set_bind_group(1, &t.cast_binds[(k == COUNT_EVERY) as usize], &[]);
        pass.set_bind_group(2, &st.peel_frame_bind, &[]);
        pass.draw(0..6, 0..tiles);
    }
}
