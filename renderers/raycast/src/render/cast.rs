//! Phase 3 of the frame (§3.2): the rays start at their first layer's entries and walk the
//! mesh, in rounds of k passes per tile ([`super::passes`], mode=passes) or to their end in one
//! dispatch per tile (mode=loop).

use std::time::Instant;

use render_core::{FrameClock, Gpu};

use super::passes::{self, run_passes, Rounds};
use super::{active_tiles, dispatch, read_counts, State};
use crate::resources::{FrameParams, Target, MAX_TILES, STAT_SLOTS};
use crate::settings::{Mode, RaycastSettings};

/// What the cast did: each tile's passes (row-major), the rounds, and the statistics slots
/// (`STAT_*` in cast.wgsl).
pub(super) struct Cast {
    pub tile_passes: Vec<u32>,
    pub rounds: Rounds,
    pub stats: Vec<u32>,
}

/// Uploads `params` (the peel's layer count and the cast's flags set), starts every ray at its
/// first entry, walks them as `s.mode` says, ends the frame's GPU timer and reads the
/// statistics back.
pub(super) fn cast(
    gpu: &Gpu,
    st: &State,
    t: &Target,
    s: &RaycastSettings,
    params: &FrameParams,
    clock: &mut FrameClock,
) -> anyhow::Result<Cast> {
    gpu.queue
        .write_buffer(&st.frame_params, 0, bytemuck::bytes_of(params));
    gpu.queue.write_buffer(&t.stats, 0, &[0u8; STAT_SLOTS * 4]);
    gpu.queue
        .write_buffer(&t.tile_counts, 0, &[0u8; MAX_TILES * 4]);
    let t_cast = Instant::now();
    let (w, h) = (t.width, t.height);
    dispatch(
        gpu,
        st,
        t,
        &st.pipes.init,
        [w.div_ceil(8), h.div_ceil(8), 1],
        clock,
    );
    let ntiles = (s.tiles * s.tiles) as usize;
    let counts = read_counts(gpu, clock, &t.tile_counts, ntiles)?;
    let mut tile_passes = vec![0u32; ntiles];
    // One dispatch per pass covers every listed tile (workgroup z = slot in the list).
    let tile_size = [params.size[2], params.size[3]];
    let grid = passes::Grid::new(tile_size, s.k);
    let rounds = match s.mode {
        Mode::Passes => run_passes(gpu, st, t, grid, counts, &mut tile_passes, clock)?,
        Mode::Loop => {
            run_loop(gpu, st, t, grid, &counts, &mut tile_passes, clock);
            Rounds::default()
        }
    };
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    st.timer.end(&mut enc);
    clock.submit(gpu, [enc.finish()]);
    let stats = clock.read_buffer(gpu, &t.stats, 0, STAT_SLOTS as u64 * 4)?;
    clock.stage("cast", t_cast);
    Ok(Cast {
        tile_passes,
        rounds,
        stats: bytemuck::cast_slice(&stats).to_vec(),
    })
}

/// mode=loop: one dispatch over the tiles any ray entered, each ray stepped to its end; such a
/// tile counts one pass.
fn run_loop(
    gpu: &Gpu,
    st: &State,
    t: &Target,
    grid: passes::Grid,
    counts: &[u32],
    tile_passes: &mut [u32],
    clock: &mut FrameClock,
) {
    let active = active_tiles(counts);
    if active.is_empty() {
        return;
    }
    gpu.queue
        .write_buffer(&t.active_tiles, 0, bytemuck::cast_slice(&active));
    let [x, y] = grid.groups;
    dispatch(
        gpu,
        st,
        t,
        &st.pipes.run_loop,
        [x, y, active.len() as u32],
        clock,
    );
    for &tile in &active {
        tile_passes[tile as usize] = 1;
    }
}
