//! Image-space sheet-buffered splatting on the GPU (Grau & Tost 2007), with the per-slab
//! buckets built on the GPU (`buckets=gpu`, the paper's pipeline) or on the CPU and uploaded
//! each frame (`buckets=cpu`, the paper's "CPU FPS" baseline of Table 1).
//!
//! Input is a voxel grid: the mesh's own (`TetMesh::source_grid`, volume data sets and
//! generated volumes) or the mesh resampled onto a grid with `grid` points along its longest
//! side (the row's counters say `resampled=1`). The relevant voxels (κ > 0 under the transfer
//! function) are selected once in `prepare`, 16 bytes each (x, y, z, value; §3.2).
//!
//! Per frame and brick (§3.1–3.6): view depth per voxel → depth sort (bitonic, the paper's,
//! or render-core's radix sort) → gather into depth order → bucket boundaries on the GPU →
//! read back only the bucket-end table (one u32 per slab) → slabs front to back: slab i
//! splats the voxels of buckets i − r … i + r with the footprint slice of their offset from
//! the slab (one table of all slices, `kernel.rs`) into its sheet, then the sheet is
//! classified (post-classification on the slab's mean value), composited under the image and
//! zeroed for the next slab.
//!
//! The paper draws each splat as a point sprite and lets the blender add it to the sheet. Here
//! a compute pass walks each footprint's pixel centres (the rasteriser's own coverage rule,
//! `coverage.rs`) and adds to the sheet in fixed point with atomics: the same sums, exact and
//! in any order. On lavapipe a splat quad's two triangles cost ~0.3 µs of set-up for one to a
//! few dozen fragments, which made StagBeetle's 69 M splats a 41 s frame (docs/profile.md).
//! Pixels already opaque discard their splats (early splat elimination, `ese`). Bricks (§4)
//! split the voxels by octants when they exceed one storage binding (or `brick=N`); they are
//! drawn in camera order, and kernels crossing a brick face are composited out of order (the
//! `border_voxels` counter).
//!
//! Orthographic and perspective cameras: slabs are planes of constant view depth; a
//! perspective footprint is scaled by focal length / depth, and each sheet's opacity uses the
//! ray's length through the slab.

mod buckets;
pub mod coverage;
mod description;
mod frame;
mod gpu;
#[doc(hidden)]
pub use gpu::gpu_layouts;
pub mod kernel;
mod prepare;
pub mod voxels;

use anyhow::{bail, Context};
use datasets::{TetMesh, VoxelVolume};
use render_core::bind::color_pass;
use render_core::gpu_sort::GpuRadixSort;
use render_core::{
    Camera, FrameClock, FrameStats, FrameTimer, Gpu, Image, MemoryLedger, Optics, Prepared,
    Renderer,
};

pub use buckets::{bucket_ends, depth, SlabGeometry};
use coverage::{FragmentCount, QuadParams};
pub use description::{from_settings, DESCRIPTION};
use frame::depth_row;
use gpu::Pipelines;
use kernel::FootprintTable;
use render_core::table_texture::TableTexture;
use voxels::VoxelSet;

/// Where the per-slab buckets are built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Buckets {
    Cpu,
    Gpu,
}

/// The GPU depth sort (with `buckets=gpu`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GpuSort {
    /// Grau & Tost §3.4 (Govindaraju et al.'s bitonic network).
    Bitonic,
    /// render-core's LSD radix sort.
    Radix,
}

/// The knobs (every one appears in the `settings` column).
#[derive(Debug, Clone, PartialEq)]
pub struct SplatSettings {
    pub buckets: Buckets,
    pub sort: GpuSort,
    /// Kernel radius in grid spacings.
    pub radius: f64,
    /// Slab thickness in grid spacings.
    pub slab: f64,
    /// Footprint slice texels per side.
    pub footprint: u32,
    /// Footprint slices per slab of voxel offset.
    pub subslices: u32,
    /// Grid points along the longest side when a mesh without its own grid is resampled.
    pub grid: usize,
    /// Largest brick in voxels; `None`: as many as one storage binding holds.
    pub brick: Option<usize>,
    /// Early splat elimination.
    pub ese: bool,
    /// A perturbation, never a configuration: every other brick's voxels drawn this many grid
    /// spacings off along x ([`voxels::VoxelSet::misalign`]); 0 draws them where they are.
    pub misalign: u32,
}

impl Default for SplatSettings {
    fn default() -> Self {
        SplatSettings {
            buckets: Buckets::Gpu,
            sort: GpuSort::Bitonic,
            radius: 2.0,
            slab: 1.0,
            footprint: 32,
            subslices: 8,
            grid: 32,
            brick: None,
            ese: true,
            misalign: 0,
        }
    }
}

/// A pixel at least this opaque drops the splats behind it (the error this allows is at most
/// 1 − ESE_ALPHA per pixel).
pub const ESE_ALPHA: f32 = 0.999;

/// Footprint rows per invocation of the splat pass (`Splat::lanes`), the most invocations one
/// voxel is split over, and the most invocations of one dispatch (a bucket of many voxels is
/// split less, so that voxels × lanes stays a u32 the dispatch can hold).
const ROWS_PER_LANE: f64 = 2.0;
const MAX_LANES: u32 = 64;
const MAX_SPLAT_INVOCATIONS: u32 = 1 << 30;

/// Transfer function table entries (linear between entries).
const TF_ENTRIES: usize = 256;

struct Targets {
    width: u32,
    height: u32,
    image: wgpu::Texture,
    image_view: wgpu::TextureView,
    /// Per pixel and ring slot two u32: a slab's fixed-point sums (splat.wgsl).
    sheet: wgpu::Buffer,
    /// Sheets in the ring, 2r + 1.
    ring: u64,
    bytes: u64,
}

struct State {
    set: VoxelSet,
    table: FootprintTable,
    pipes: Pipelines,
    bricks: Vec<wgpu::Buffer>,
    /// The footprint slices, an `R32Float` 3D texture ((footprint + 2)² texels a slice row).
    table_view: wgpu::TextureView,
    table_sampler: wgpu::Sampler,
    tf_buf: wgpu::Buffer,
    frame_buf: wgpu::Buffer,
    slab_buf: wgpu::Buffer,
    bitonic_buf: wgpu::Buffer,
    keys: wgpu::Buffer,
    vals: wgpu::Buffer,
    sorted: wgpu::Buffer,
    ends: wgpu::Buffer,
    /// One u32: splat fragments dropped by early splat elimination this frame.
    ese_dropped: wgpu::Buffer,
    radix: Option<GpuRadixSort>,
    cpu: buckets::CpuBuckets,
    max_slabs: u32,
    length_unit: f64,
    ledger: MemoryLedger,
    frame_bytes: u64,
    timer: FrameTimer,
}

/// The splat renderer.
pub struct Splat {
    pub settings: SplatSettings,
    state: Option<State>,
    targets: Option<Targets>,
    /// The last view's splat coverage (work counters are derived once per view).
    coverage: Option<(QuadParams, SlabGeometry, FragmentCount)>,
    /// Test hook: every splat fragment is counted as dropped (`ese_dropped_fragments` becomes
    /// the GPU's own count of splat fragments) and the image stays empty.
    count_every_fragment: bool,
    /// Test hook: each slab splats its buckets i − r … i + r on its own (the paper's order),
    /// instead of each bucket once into a ring of sheets.
    slab_by_slab: bool,
    /// Test hook: invocations per voxel in the splat pass, whatever the adapter
    /// (`Splat::lanes`).
    forced_lanes: Option<u32>,
    /// Test hook: the footprint table loaded and interpolated by hand, the path of devices
    /// that cannot filter `R32Float`.
    table_loads: bool,
}

/// What one brick of one frame did.
#[derive(Default)]
struct BrickStats {
    slabs: u64,
    splats: u64,
    buckets_ms: f64,
    splat_ms: f64,
}

impl Splat {
    pub fn new(settings: SplatSettings) -> Splat {
        Splat {
            settings,
            state: None,
            targets: None,
            coverage: None,
            count_every_fragment: false,
            slab_by_slab: false,
            forced_lanes: None,
            table_loads: false,
        }
    }

    /// Whether the footprint table is sampled with trilinear filtering: where the device
    /// filters `R32Float` (`FLOAT32_FILTERABLE`) and no test asked for the loads.
    fn table_filtered(&self, gpu: &Gpu) -> bool {
        !self.table_loads && TableTexture::filterable_on(gpu)
    }

    /// Every GPU allocation of the prepared data (after `prepare`).
    pub fn memory(&self) -> Option<&MemoryLedger> {
        self.state.as_ref().map(|s| &s.ledger)
    }

    /// The voxels prepared (after `prepare`).
    pub fn voxels(&self) -> Option<&VoxelSet> {
        self.state.as_ref().map(|s| &s.set)
    }
}

impl Renderer for Splat {
    fn algorithm(&self) -> &'static str {
        "splat"
    }

    fn settings(&self) -> render_core::Settings {
        description::settings_of(&self.settings)
    }

    fn prepare(
        &mut self,
        gpu: &Gpu,
        mesh: &std::sync::Arc<TetMesh>,
        optics: &Optics,
    ) -> anyhow::Result<Prepared> {
        let grid = self.settings.grid;
        self.prepare_set(gpu, optics, mesh.num_tets(), |cap| {
            VoxelSet::new(mesh, optics, grid, cap)
        })
    }

    fn draws_voxels(&self) -> bool {
        true
    }

    fn prepare_voxels(
        &mut self,
        gpu: &Gpu,
        volume: &VoxelVolume,
        optics: &Optics,
    ) -> anyhow::Result<Prepared> {
        self.prepare_set(gpu, optics, volume.num_tets(), |cap| {
            VoxelSet::from_volume(volume, optics, cap)
        })
    }

    fn render(&mut self, gpu: &Gpu, camera: &Camera) -> anyhow::Result<FrameStats> {
        self.state
            .as_ref()
            .context("splat: render before prepare")?;
        let mut clock = FrameClock::start();
        self.ensure_targets(gpu, camera.width, camera.height)?;
        let st = self.state.as_ref().unwrap();
        let geom = self.geometry(st, camera);
        if geom.num_slabs > st.max_slabs {
            bail!(
                "splat: {} slabs needed, {} prepared (camera inside the volume?)",
                geom.num_slabs,
                st.max_slabs
            );
        }
        let row = depth_row(camera);
        let fwd = camera.forward();
        let order = st.set.brick_order(camera.eye, fwd, camera.is_perspective());
        let t = self.targets.as_ref().unwrap();
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        st.timer.begin(&mut enc);
        enc.clear_buffer(&st.ese_dropped, 0, None);
        color_pass(&mut enc, "splat clear", &t.image_view, true, true, None);
        clock.submit(gpu, [enc.finish()]);
        let rect = self.composite_rect(camera).expect("prepared");
        let lanes = self.lanes(gpu, camera, &geom);
        let mut stats = BrickStats::default();
        for b in order {
            if self.state.as_ref().unwrap().set.bricks[b].range.is_empty() {
                continue;
            }
            self.write_frame(gpu, camera, &geom, b);
            let (ends, _) = self.buckets(gpu, b, &geom, row, false, &mut stats, &mut clock)?;
            self.draw_brick(gpu, &geom, &ends, rect, lanes, &mut stats, &mut clock);
        }
        let st = self.state.as_ref().unwrap();
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        st.timer.end(&mut enc);
        clock.submit(gpu, [enc.finish()]);
        clock.wait(gpu)?;
        let times = clock.finish().with_stages([
            ("buckets".into(), stats.buckets_ms),
            ("splat".into(), stats.splat_ms),
        ]);
        let total_ms = times.total_ms;
        // Work counters, after the timed frame: the quads' pixels are derived on the CPU once
        // per view (`coverage.rs`).
        let cover = self.fragment_count(camera)?;
        let st = self.state.as_ref().unwrap();
        let gpu_ms = st.timer.gpu_ms(gpu)?;
        // Counter readback, after the timed frame.
        let ese_dropped = u32::from_le_bytes(
            gpu.read_buffer(&st.ese_dropped, 0, 4)?[..4]
                .try_into()
                .expect("4 bytes read"),
        );
        let eff = st.set.voxels.len() as f64;
        let t = self.targets.as_ref().unwrap();
        Ok(times.stats(
            gpu_ms,
            st.frame_bytes + t.bytes,
            vec![
                ("effective_voxels".into(), eff),
                ("grid_points".into(), st.set.grid_points as f64),
                ("resampled".into(), st.set.resampled as u8 as f64),
                ("grid_x".into(), st.set.dims[0] as f64),
                ("grid_y".into(), st.set.dims[1] as f64),
                ("grid_z".into(), st.set.dims[2] as f64),
                ("bricks".into(), st.set.bricks.len() as f64),
                ("border_voxels".into(), st.set.border_voxels as f64),
                ("slabs".into(), stats.slabs as f64),
                ("splats".into(), stats.splats as f64),
                ("splat_fragments".into(), cover.fragments as f64),
                // Each drawn slab composites one viewport-covering triangle, scissored to the
                // rectangle its sheet can hold (the splats themselves are a compute pass:
                // `splat_fragments`).
                (
                    "fragments".into(),
                    stats.slabs as f64
                        * (rect[2].saturating_sub(rect[0]) as f64)
                        * (rect[3].saturating_sub(rect[1]) as f64),
                ),
                ("triangles".into(), stats.slabs as f64),
                (
                    match self.settings.buckets {
                        Buckets::Cpu => "cpu_sort_keys",
                        Buckets::Gpu => "gpu_sort_keys",
                    }
                    .into(),
                    eff,
                ),
                // Early splat elimination drops these; each pixel it touches is already at
                // least ESE_ALPHA opaque, so it changes that pixel by at most 1 − ESE_ALPHA.
                ("ese_dropped_fragments".into(), ese_dropped as f64),
                // The paper's (x, y, z, value) texel.
                (
                    "bytes_per_voxel".into(),
                    std::mem::size_of::<[f32; 4]>() as f64,
                ),
                (
                    "voxels_per_sec".into(),
                    if total_ms > 0.0 {
                        eff / (total_ms * 1e-3)
                    } else {
                        0.0
                    },
                ),
            ],
        ))
    }

    fn read_image(&mut self, gpu: &Gpu) -> anyhow::Result<Image> {
        let t = self
            .targets
            .as_ref()
            .context("splat: read_image before render")?;
        gpu.read_rgba32f(&t.image)
    }
}

impl std::fmt::Debug for Splat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Splat")
            .field("settings", &self.settings)
            .finish()
    }
}
