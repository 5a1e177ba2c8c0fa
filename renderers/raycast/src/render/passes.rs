//! Phase 3 in mode=passes (§2.3, §3.2 phases 3a–3b), as the paper spends its passes: per tile
//! and per peeling layer, rounds of [`COUNT_EVERY`] passes of one ray step each; the last pass
//! of a round counts the tile's rays still inside the mesh (the paper's occlusion query). A
//! tile at zero has finished its layer: its rays start again from their next layer entries
//! (`load_layer`), and a tile where none does is done. A tile's passes are thus the sum over
//! its layers of the longest walk in each, rounded up to whole rounds.

use render_core::{FrameClock, Gpu};

use super::{active_tiles, read_counts, State};
use crate::resources::{Target, TilePipelines};
use crate::COUNT_EVERY;

/// What the rounds did: their number, and the tile rectangles drawn (two triangles each) where
/// the passes are drawn rather than dispatched.
#[derive(Default)]
pub(super) struct Rounds {
    pub rounds: u32,
    pub rectangles: u64,
    /// Times a tile started its rays again from their next layer.
    pub layer_loads: u64,
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
    let mut rounds = Rounds::default();
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
        // The tiles whose rays have all left their layer load the next one.
        let finished: Vec<u32> = active
            .into_iter()
            .filter(|&tile| counts[tile as usize] == 0)
            .collect();
        if !finished.is_empty() {
            let loaded = load_layers(gpu, st, t, groups, &finished, ntiles, clock)?;
            for &tile in &finished {
                counts[tile as usize] = loaded[tile as usize];
            }
            rounds.layer_loads += finished.len() as u64;
        }
    }
    Ok(rounds)
}

/// Starts the rays of `tiles` (all of whose rays have left their layer) again from their next
/// layer entries; returns every tile's count of rays that started again (0 where not listed).
fn load_layers(
    gpu: &Gpu,
    st: &State,
    t: &Target,
    groups: [u32; 2],
    tiles: &[u32],
    ntiles: usize,
    clock: &mut FrameClock,
) -> anyhow::Result<Vec<u32>> {
    gpu.queue
        .write_buffer(&t.active_tiles, 0, bytemuck::cast_slice(tiles));
    gpu.queue
        .write_buffer(&t.tile_counts, 0, &[0u8; crate::resources::MAX_TILES * 4]);
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&st.pipes.load_layer);
        pass.set_bind_group(0, &st.mesh_bind, &[]);
        pass.set_bind_group(1, &t.cast_binds[0], &[]);
        pass.dispatch_workgroups(groups[0], groups[1], tiles.len() as u32);
    }
    clock.submit(gpu, [enc.finish()]);
    read_counts(gpu, clock, &t.tile_counts, ntiles)
}

/// One round as the paper draws it: the depth update (rays that have ended or left their layer
/// to depth 0, the others to 1; the first round clears the depth first), then [`COUNT_EVERY`] passes of a rectangle per active tile, each
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
