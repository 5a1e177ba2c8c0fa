//! The paper's faithful single pass (`mode=fragment-race`: every fragment reads, updates and
//! writes its pixel's k-buffer in storage, HAVS §4, Fig. 5) held to its CPU twin
//! (`kbuffer.rs`), pixel by pixel.
//!
//! The fragments come from the GPU itself: the same view drawn in `mode=race-free` stores each
//! pixel's fragments with their submission index (the face's place in the sorted order), so
//! the twin sees exactly the depths the shader computed, in the order the faces were drawn.
//! Streamed through `KBuffer`, they give per pixel the fragment count and the out-of-order
//! pops before the drain pass, which the racy pass records in its pixel (`Pixel.info.y`, `.z`),
//! and the pops of the drain, which only reach the frame's counter.
//!
//! Where fragments of one pixel are shaded one after the other in primitive order (a CPU
//! adapter such as lavapipe: one thread per screen tile, primitives in order) the racy pass
//! *is* the twin: every per-pixel count must agree exactly. On a GPU that shades them
//! concurrently the read-modify-write can lose updates — the race the paper accepted — and
//! only the derived relation "the racy pass counts no more fragments than were drawn" holds.

use havs::kbuffer::{Fragment, KBuffer, Tag, TagScheme};
use havs::{Havs, HavsSettings, Mode};
use render_core::{
    fixed_viewpoints, Camera, FrameStats, Gpu, Optics, Projection, Renderer, TransferFunction,
};

fn gpu() -> Gpu {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", "/tmp");
    }
    Gpu::new().expect("a wgpu adapter (lavapipe: apt-get install mesa-vulkan-drivers)")
}

fn counter(c: &[(String, f64)], name: &str) -> u64 {
    c.iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no counter {name}"))
        .1 as u64
}

/// The tag `kbuffer.wgsl` decodes from an entry's v = s + 2·tag (`kb_tag`).
fn tag_of(v: f32) -> Tag {
    Tag::from_index(((v - 0.5) * 0.5).round().max(0.0) as u32)
}

/// Per pixel, the twin's (fragments, pops before the drain, pops of the drain) for the GPU's
/// own fragment lists, each put in submission order.
fn twin_counts(lists: &[Vec<(f32, f32, u32)>], k: usize) -> Vec<[u32; 3]> {
    lists
        .iter()
        .map(|list| {
            let mut l = list.clone();
            l.sort_by_key(|f| f.2);
            let mut kb = KBuffer::new(k, TagScheme::Two);
            for &(v, d, _) in &l {
                kb.insert(Fragment {
                    scalar: (v - 2.0 * tag_of(v) as u32 as f32).clamp(0.0, 1.0),
                    depth: d,
                    tag: tag_of(v),
                });
            }
            let before = kb.out_of_order;
            kb.drain(&mut vec![]);
            [l.len() as u32, before, kb.out_of_order - before]
        })
        .collect()
}

fn render(
    gpu: &Gpu,
    mesh: &std::sync::Arc<datasets::TetMesh>,
    optics: &Optics,
    s: HavsSettings,
    camera: &Camera,
) -> (Havs, FrameStats) {
    let mut r = Havs::new(s);
    r.prepare(gpu, mesh, optics).unwrap();
    let stats = r.render(gpu, camera).unwrap();
    (r, stats)
}

#[test]
fn the_racy_single_pass_counts_what_its_cpu_twin_counts_per_pixel() {
    let gpu = gpu();
    // The sliver onion breaks a k = 2 buffer almost everywhere, so the counts to
    // compare are not all zero; 48² keeps the per-pixel lists short enough to check quickly.
    let mesh = std::sync::Arc::new(datasets::generate::from_spec("onion:4k", 1).unwrap());
    let optics = Optics::for_mesh(TransferFunction::preset("low-opacity").unwrap(), &mesh);
    // Out-of-order pops over all three views: k = 3 has a handful (8 on lavapipe, none on an
    // H200, whose rasteriser puts some fragments elsewhere), k = 2 thousands.
    let mut all_pops = 0;
    for (k, projection) in [
        (2, Projection::default()),
        (2, Projection::Orthographic),
        (3, Projection::default()),
    ] {
        let camera = Camera::fit(&mesh.bounds(), &fixed_viewpoints()[6], projection, 48, 48);
        // Early termination off: with it the racy pass skips fragments of opaque pixels and
        // the two passes would count different streams.
        let base = HavsSettings {
            k,
            early_termination: false,
            table_scalar: 32,
            table_length: 32,
            ..Default::default()
        };
        let (free, free_stats) = render(
            &gpu,
            &mesh,
            &optics,
            HavsSettings {
                mode: Mode::RaceFree,
                ..base
            },
            &camera,
        );
        let lists = free.read_fragment_lists(&gpu).unwrap();
        let twin = twin_counts(&lists, k as usize);
        let (racy, racy_stats) = render(
            &gpu,
            &mesh,
            &optics,
            HavsSettings {
                mode: Mode::FragmentRace,
                ..base
            },
            &camera,
        );
        let got = racy.read_pixel_counts(&gpu).unwrap();
        assert_eq!(got.len(), twin.len());
        let fragments: u64 = twin.iter().map(|t| t[0] as u64).sum();
        let pops: u64 = twin.iter().map(|t| (t[1] + t[2]) as u64).sum();
        let what = format!("onion:4k k={k} {projection:?}");
        assert!(
            fragments > 10 * 48 * 48 / 4,
            "{what}: only {fragments} fragments"
        );
        all_pops += pops;
        eprintln!(
            "{what}: twin {fragments} fragments, {pops} out-of-order pops; racy pass {} / {}; \
             lost to the race {}; race-free pass {} / {} (lists over 512: {})",
            counter(&racy_stats.counters, "fragments"),
            counter(&racy_stats.counters, "kbuffer_out_of_order"),
            counter(&racy_stats.counters, "race_lost_updates"),
            counter(&free_stats.counters, "fragments"),
            counter(&free_stats.counters, "kbuffer_out_of_order"),
            counter(&free_stats.counters, "lists_over_512"),
        );
        // The race-free pass stored exactly the fragments the twin was given. (Its own
        // out-of-order count is not compared: on lavapipe it differs from the racy pass's and
        // the twin's on the same fragments, an open question for the renderer.)
        assert_eq!(
            counter(&free_stats.counters, "fragments"),
            fragments,
            "{what}: race-free"
        );

        let sequential = gpu.adapter.is_cpu();
        let mut wrong = vec![];
        for (i, (g, t)) in got.iter().zip(&twin).enumerate() {
            // The atomic count of fragments shaded is exact everywhere.
            let ok = g[2] == t[0]
                && if sequential {
                    g[0] == t[0] && g[1] == t[1]
                } else {
                    g[0] <= t[0]
                };
            if !ok {
                wrong.push(format!(
                    "pixel ({}, {}): racy {} fragments {} pops ({} shaded), twin {} fragments {} pops",
                    i % 48,
                    i / 48,
                    g[0],
                    g[1],
                    g[2],
                    t[0],
                    t[1]
                ));
            }
        }
        assert!(
            wrong.is_empty(),
            "{what}: {} of {} pixels differ ({}):\n{}",
            wrong.len(),
            got.len(),
            gpu.adapter.name,
            wrong[..wrong.len().min(10)].join("\n")
        );
        // On every adapter: each fragment the twin was given was shaded once, and either the
        // racy per-pixel counts kept it or the frame counts it as lost to the race.
        let lost = counter(&racy_stats.counters, "race_lost_updates");
        assert_eq!(
            counter(&racy_stats.counters, "fragments") + lost,
            fragments,
            "{what}: racy fragments + race_lost_updates ({lost})"
        );
        if sequential {
            assert_eq!(
                lost, 0,
                "{what}: no update is lost where fragments run in order"
            );
            assert_eq!(
                counter(&racy_stats.counters, "kbuffer_out_of_order"),
                pops,
                "{what}: racy total"
            );
            assert_eq!(
                counter(&racy_stats.counters, "fragments"),
                fragments,
                "{what}: racy total"
            );
        }
    }
    assert!(
        all_pops > 0,
        "the twin finds no out-of-order pop in any view; the pop counts compare nothing"
    );
}
