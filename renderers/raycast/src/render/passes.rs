//! Phase 3 in mode=passes (§2.3, §3.2 phases 3a–3b), as the paper spends its passes: per tile
//! and per peeling layer, rounds of k passes ([`crate::RaycastSettings::k`]) of one ray step each; the last pass
//! of a round counts the tile's rays still inside the mesh (the paper's occlusion query). A
//! tile at zero has finished its layer: its rays start again from their next layer entries
//! (`load_layer`), and a tile where none does is done. A tile's passes are thus the sum over
//! its layers of the longest walk in each, rounded up to whole rounds.

use render_core::{FrameClock, Gpu};

use super::{active_tiles, dispatch, read_counts, State};
use crate::resources::{Target, TilePipelines};

/// The dispatch of one pass over the listed tiles (workgroups per tile), and k.
#[derive(Clone, Copy)]
pub(super) struct Grid {
    pub groups: [u32; 2],
    pub k: u32,
}

impl Grid {
    /// 8×8 workgroups over a tile of `tile_size` pixels.
    pub fn new(tile_size: [u32; 2], k: u32) -> Grid {
        Grid {
            groups: [tile_size[0].div_ceil(8), tile_size[1].div_ceil(8)],
            k,
        }
    }
}

/// One round drawn as rectangles: the active tiles, whether it is the frame's first, and k.
#[derive(Clone, Copy)]
struct Round {
    tiles: u32,
    first: bool,
    k: u32,
}

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
    grid: Grid,
    mut counts: Vec<u32>,
    tile_passes: &mut [u32],
    clock: &mut FrameClock,
) -> anyhow::Result<Rounds> {
    let ntiles = tile_passes.len();
    let Grid { groups, k } = grid;
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
                let round = Round {
                    tiles: active.len() as u32,
                    first: rounds.rounds == 0,
                    k,
                };
                encode_tile_round(&mut enc, st, t, pipes, zcull, round);
                rounds.rectangles += active.len() as u64 * (k as u64 + 1);
            }
            None => {
                let mut pass = enc.begin_compute_pass(&Default::default());
                pass.set_pipeline(&st.pipes.step);
                pass.set_bind_group(0, &st.mesh_bind, &[]);
                for pass_index in 0..k {
                    let count = (pass_index + 1 == k) as usize;
                    pass.set_bind_group(1, &t.cast_binds[count], &[]);
                    pass.dispatch_workgroups(groups[0], groups[1], active.len() as u32);
                }
            }
        }
        clock.submit(gpu, [enc.finish()]);
        for &tile in &active {
            tile_passes[tile as usize] += k;
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
    let [x, y] = groups;
    dispatch(
        gpu,
        st,
        t,
        &st.pipes.load_layer,
        [x, y, tiles.len() as u32],
        clock,
    );
    read_counts(gpu, clock, &t.tile_counts, ntiles)
}

/// One round as the paper draws it: the depth update (rays that have ended or left their layer
/// to depth 0, the others to 1; the first round clears the depth first), then `k` passes of a rectangle per active tile, each
/// its own render pass so that a pass sees the rays the one before it stored.
fn encode_tile_round(
    enc: &mut wgpu::CommandEncoder,
    st: &State,
    t: &Target,
    pipes: &TilePipelines,
    zcull: &wgpu::TextureView,
    round: Round,
) {
    let Round { tiles, first, k } = round;
    for pass_index in 0..=k {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("raycast tile pass"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: zcull,
                depth_ops: Some(wgpu::Operations {
                    load: if first && pass_index == 0 {
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
        pass.set_pipeline(if pass_index == 0 {
            &pipes.cull
        } else {
            &pipes.step
        });
        pass.set_bind_group(0, &st.mesh_bind, &[]);
        pass.set_bind_group(1, &t.cast_binds[(pass_index == k) as usize], &[]);
        pass.set_bind_group(2, &st.peel_frame_bind, &[]);
        pass.draw(0..6, 0..tiles);
    }
}
