//! The frame's work counters, from the peel, the cast's statistics and the prepared mesh.

use super::cast::Cast;
use super::peel::Peeled;
use super::State;
use crate::settings::{Mode, RaycastSettings};

// Slots of the statistics buffer (`STAT_*` in cast.wgsl).
const STAT_ENTERED: usize = 0;
const STAT_TERMINATED: usize = 1;
const STAT_STALLED: usize = 2;
const STAT_DROPPED: usize = 3;
const STAT_SKIPPED: usize = 4;
const STAT_STEPS: usize = 5;
const STAT_MAX_STEPS: usize = 6;
const STAT_STEPS_HIGH: usize = 7;

/// The counters of a frame that peeled `peeled` and cast `cast`.
pub(super) fn counters(
    st: &State,
    s: &RaycastSettings,
    peeled: &Peeled,
    cast: &Cast,
) -> Vec<(String, f64)> {
    let Cast {
        tile_passes,
        rounds,
        stats,
    } = cast;
    let entered = stats[STAT_ENTERED] as f64;
    // Tets crossed by all rays together (one step = one ray-tet exit computation and one
    // composited segment), the work the roofline's ray-step rate measures.
    let ray_steps = ((stats[STAT_STEPS_HIGH] as u64) << 32 | stats[STAT_STEPS] as u64) as f64;
    let max_passes = tile_passes.iter().copied().max().unwrap_or(0);
    let mean_passes = tile_passes.iter().map(|&p| p as f64).sum::<f64>() / tile_passes.len() as f64;
    let empty_tiles = tile_passes.iter().filter(|&&p| p == 0).count();
    let steps_mean = if entered > 0.0 {
        ray_steps / entered
    } else {
        0.0
    };
    // Every peeling layer draws all boundary faces (the last draw finds its layer empty or
    // fills the spare slot that counts dropped re-entries); passes drawn as tile rectangles
    // add two triangles a rectangle.
    let triangles =
        (st.face_vertices / 3) as f64 * peeled.draws as f64 + 2.0 * rounds.rectangles as f64;
    let mut counters = vec![
        ("passes_max", max_passes as f64),
        ("passes_mean", mean_passes),
        ("tiles_empty", empty_tiles as f64),
        ("count_rounds", rounds.rounds as f64),
        ("peel_layers", peeled.layers as f64),
        ("rays", entered),
        ("steps_mean", steps_mean),
        ("steps_max", stats[STAT_MAX_STEPS] as f64),
        ("ray_steps", ray_steps),
        ("triangles", triangles),
        ("early_terminated_rays", stats[STAT_TERMINATED] as f64),
        ("stalled_rays", stats[STAT_STALLED] as f64),
        ("dropped_reentries", stats[STAT_DROPPED] as f64),
        ("skipped_entries", stats[STAT_SKIPPED] as f64),
        (
            "mesh_bytes_per_tet",
            st.mesh_bytes as f64 / st.tets.max(1) as f64,
        ),
        ("mesh_padding_bytes", st.mesh_padding_bytes as f64),
        ("table_bytes", st.table.bytes as f64),
        // An adapter that cannot filter Rgba32Float samples the table nearest (counted).
        ("table_filter_nearest", !st.table.filterable as u8 as f64),
        ("mesh_bindings", st.mesh_bindings as f64),
    ];
    if s.mode == Mode::Passes {
        // The passes' and depth updates' rectangles (0 where the passes are compute dispatches).
        counters.push(("tile_rectangles", rounds.rectangles as f64));
        // Times a tile restarted its passes from its next peeling layer (§3.2 phase 3a).
        counters.push(("layer_loads", rounds.layer_loads as f64));
    }
    counters
        .into_iter()
        .map(|(name, value)| (name.to_string(), value))
        .collect()
}
