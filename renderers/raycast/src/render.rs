//! The renderer: its state, what `prepare` builds (`render/prepare.rs`), and a frame as the
//! paper's phases (`frame`).

use anyhow::{anyhow, bail, Context};
use datasets::TetMesh;
use render_core::bind;
use render_core::gpu::{Lifetime, MemoryLedger};
use render_core::table_texture::TableTexture;
use render_core::{
    Camera, FrameClock, FrameStats, FrameTimer, Gpu, Image, Optics, Prepared, Renderer, Settings,
};

use crate::layout::{MeshLayout, TetRef};
use crate::resources::{FrameParams, Pipelines, Target, TileRect};
use crate::settings::{RaycastSettings, TableKind};
use crate::step::{LayerEntry, RayFrame};
use crate::{ET_OPACITY, PEEL_BIAS, TABLE_LENGTH, TABLE_SCALAR};

mod cast;
mod counters;
mod passes;
mod peel;
mod prepare;
use cast::cast;
use counters::counters;
use peel::peel;

const FLAG_ET: u32 = 1;
const FLAG_TABLE3D: u32 = 2;
const FLAG_COUNT_DROPPED: u32 = 4;
/// The 2D table's entry composited without the scaling by length (`unscaled=1`, a positive
/// control; `cast.wgsl`'s `lookup`).
const FLAG_UNSCALED: u32 = 8;

/// Tiled ray caster (`raycast`).
pub struct Raycast {
    pub settings: RaycastSettings,
    /// Bytes per mesh texture layer when smaller than the adapter's storage-binding limit
    /// (tests split small meshes across layers this way).
    max_binding: Option<u64>,
    /// Bytes per mesh texture when smaller than [`crate::layout::MESH_TEXTURE_BYTES`] (tests
    /// split small meshes across textures this way).
    max_texture_bytes: Option<u64>,
    /// mode=passes as compute dispatches even where the device can draw it as tile rectangles
    /// (tests compare the two).
    compute_passes: bool,
    state: Option<State>,
}

struct State {
    /// The OCS origin of the packed mesh ([`MeshLayout::origin`]).
    origin: [f64; 3],
    /// Layers of the mesh texture and its bytes. The packed texels themselves live
    /// only on the GPU: a host copy was the mesh again at 144 B/tet (2.9 GB at 20 M tets).
    mesh_bindings: usize,
    mesh_bytes: u64,
    mesh_padding_bytes: u64,
    /// The binding size the mesh was packed for, so that [`Raycast::layout`] packs it again
    /// the same way.
    max_binding: u64,
    tets: u64,
    ledger: MemoryLedger,
    pipes: Pipelines,
    frame_params: wgpu::Buffer,
    mesh_bind: wgpu::BindGroup,
    /// `frame_params` as the peel's uniform block (group 2).
    peel_frame_bind: wgpu::BindGroup,
    faces: wgpu::Buffer,
    face_vertices: u32,
    table: TableTexture,
    /// 1 / (longest edge) for the 3D table, 1 / (fixed length) for the 2D one.
    inv_table_length: f32,
    length_unit: f64,
    max_steps: u32,
    target: Option<Target>,
    /// Bytes of the viewport-sized buffers and textures of `target`.
    target_bytes: u64,
    timer: FrameTimer,
    last: Option<LastFrame>,
}

/// What the last frame did, for counters, the pass map and tests.
#[derive(Debug, Clone)]
struct LastFrame {
    camera: Camera,
    layers_used: u32,
    tile_passes: Vec<u32>,
    tile_size: [u32; 2],
}

/// Per-pixel results of the last frame, read back for tests and the pass map.
#[derive(Debug, Clone)]
pub struct PassData {
    pub width: u32,
    pub height: u32,
    /// Steps (tets crossed) per pixel.
    pub steps: Vec<u32>,
    /// Peeling layers filled, and per pixel the entries of each (layer-major).
    pub layers_used: u32,
    pub layers: Vec<Vec<Option<LayerEntry>>>,
    /// Passes each tile ran (row-major), and the tile size in pixels.
    pub tile_passes: Vec<u32>,
    pub tile_size: [u32; 2],
    /// The ray parameters of the frame (object coordinates).
    pub ray_frame: RayFrame,
    pub bias: f32,
    pub max_steps: u32,
}

impl Raycast {
    pub fn new(settings: RaycastSettings) -> Raycast {
        Raycast {
            settings,
            max_binding: None,
            max_texture_bytes: None,
            compute_passes: false,
            state: None,
        }
    }

    /// Splits the mesh into texture layers of at most `bytes` (rounded down to whole tets).
    pub fn with_max_binding(mut self, bytes: u64) -> Raycast {
        self.max_binding = Some(bytes);
        self
    }

    /// Splits the mesh texture into textures of at most `bytes` (at least one layer each).
    pub fn with_max_texture_bytes(mut self, bytes: u64) -> Raycast {
        self.max_texture_bytes = Some(bytes);
        self
    }

    /// Runs mode=passes as compute dispatches, the path of devices without forced early depth
    /// tests, instead of tile rectangles.
    pub fn with_compute_passes(mut self) -> Raycast {
        self.compute_passes = true;
        self
    }

    fn state(&self) -> anyhow::Result<&State> {
        self.state
            .as_ref()
            .ok_or_else(|| anyhow!("raycast: prepare first"))
    }

    /// The packed mesh as the GPU holds it, packed again on the host (for the CPU twin;
    /// `mesh` and `optics` must be those of the prepare).
    pub fn layout(&self, mesh: &TetMesh, optics: &Optics) -> anyhow::Result<MeshLayout> {
        MeshLayout::build(mesh, optics, self.state()?.max_binding)
    }

    /// Runs the shader's `exit_of` for arbitrary rays: (origin, direction, tet, λ at entry) →
    /// (exit face, next tet, λ exit, s exit). For tests against [`crate::step::exit_of`].
    pub fn probe(
        &self,
        gpu: &Gpu,
        rays: &[([f32; 3], [f32; 3], TetRef, f32)],
    ) -> anyhow::Result<Vec<(u32, TetRef, f32, f32)>> {
        let st = self.state()?;
        let mut input: Vec<[u32; 4]> = Vec::with_capacity(rays.len() * 3);
        for (o, d, t, l) in rays {
            let f = |v: f32| v.to_bits();
            input.push([f(o[0]), f(o[1]), f(o[2]), f(*l)]);
            input.push([f(d[0]), f(d[1]), f(d[2]), 0]);
            input.push([t.chunk, t.local, 0, 0]);
        }
        let mut ledger = MemoryLedger::default();
        let inbuf = ledger.buffer_init(
            gpu,
            "raycast probe in",
            Lifetime::PerFrame,
            bytemuck::cast_slice(&input),
            wgpu::BufferUsages::STORAGE,
        )?;
        let out = ledger.buffer(
            gpu,
            "raycast probe out",
            Lifetime::PerFrame,
            rays.len() as u64 * 32,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let entries = bind::whole_from(0, &[&inbuf, &out]);
        let bind = gpu.bind_group("raycast probe", &st.pipes.layouts.probe, &entries);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&st.pipes.probe);
            pass.set_bind_group(0, &st.mesh_bind, &[]);
            pass.set_bind_group(1, &bind, &[]);
            pass.dispatch_workgroups((rays.len() as u32).div_ceil(64), 1, 1);
        }
        gpu.queue.submit([enc.finish()]);
        let bytes = gpu.read_buffer(&out, 0, rays.len() as u64 * 32)?;
        let raw: &[[u32; 4]] = bytemuck::cast_slice(&bytes);
        Ok((0..rays.len())
            .map(|k| {
                let a = raw[2 * k];
                let b = raw[2 * k + 1];
                (
                    a[0],
                    TetRef {
                        chunk: a[1],
                        local: a[2],
                    },
                    f32::from_bits(a[3]),
                    f32::from_bits(b[0]),
                )
            })
            .collect())
    }

    /// Steps per pixel, peeling layers and passes per tile of the last frame.
    pub fn pass_data(&self, gpu: &Gpu) -> anyhow::Result<PassData> {
        let st = self.state()?;
        let (t, last) = match (&st.target, &st.last) {
            (Some(t), Some(l)) => (t, l),
            _ => bail!("raycast: render before pass_data"),
        };
        let pixels = t.width as u64 * t.height as u64;
        let aux = gpu.read_buffer(&t.aux, 0, pixels * 8)?;
        let aux: &[[u32; 2]] = bytemuck::cast_slice(&aux);
        let mut layers = Vec::new();
        for l in 0..last.layers_used {
            layers.push(read_layer(gpu, &t.layers, l, t.width, t.height)?);
        }
        Ok(PassData {
            width: t.width,
            height: t.height,
            steps: aux.iter().map(|a| a[1]).collect(),
            layers_used: last.layers_used,
            layers,
            tile_passes: last.tile_passes.clone(),
            tile_size: last.tile_size,
            ray_frame: RayFrame::new(&last.camera, st.origin),
            bias: (PEEL_BIAS * st.length_unit) as f32,
            max_steps: st.max_steps,
        })
    }
}

/// Reads one layer of the peeling texture.
fn read_layer(
    gpu: &Gpu,
    tex: &wgpu::Texture,
    layer: u32,
    w: u32,
    h: u32,
) -> anyhow::Result<Vec<Option<LayerEntry>>> {
    debug_assert_eq!((tex.width(), tex.height()), (w, h));
    let bytes = gpu.read_texture_layer(tex, layer)?;
    let texels: &[[u32; 4]] = bytemuck::cast_slice(&bytes);
    Ok(texels.iter().map(|&t| LayerEntry::decode(t)).collect())
}

fn tile_rects(w: u32, h: u32, n: u32) -> ([u32; 2], Vec<TileRect>) {
    let (tw, th) = (w.div_ceil(n), h.div_ceil(n));
    let mut v = Vec::new();
    for ty in 0..n {
        for tx in 0..n {
            v.push(TileRect {
                origin: [(tx * tw).min(w), (ty * th).min(h)],
                end: [((tx + 1) * tw).min(w), ((ty + 1) * th).min(h)],
            });
        }
    }
    ([tw, th], v)
}

impl Renderer for Raycast {
    fn algorithm(&self) -> &'static str {
        "raycast"
    }

    fn settings(&self) -> Settings {
        self.settings.to_settings()
    }

    fn prepare(
        &mut self,
        gpu: &Gpu,
        mesh: &std::sync::Arc<TetMesh>,
        optics: &Optics,
    ) -> anyhow::Result<Prepared> {
        self.state = None;
        self.settings.validate()?;
        let state = State::new(gpu, self, mesh, optics)?;
        let prepared = Prepared {
            persistent_bytes: state.ledger.persistent,
            tets: state.tets,
        };
        self.state = Some(state);
        Ok(prepared)
    }

    fn render(&mut self, gpu: &Gpu, camera: &Camera) -> anyhow::Result<FrameStats> {
        let s = self.settings;
        let st = self
            .state
            .as_mut()
            .ok_or_else(|| anyhow!("raycast: render before prepare"))?;
        frame(gpu, st, &s, camera)
    }

    fn read_image(&mut self, gpu: &Gpu) -> anyhow::Result<Image> {
        let st = self.state()?;
        let t = st
            .target
            .as_ref()
            .ok_or_else(|| anyhow!("raycast: read_image before render"))?;
        let bytes = gpu
            .read_buffer(&t.colours, 0, t.width as u64 * t.height as u64 * 16)
            .context("raycast: reading the image back")?;
        let mut img = Image::new(t.width, t.height);
        img.pixels.copy_from_slice(bytemuck::cast_slice(&bytes));
        Ok(img)
    }

    fn extra_image(&mut self, gpu: &Gpu) -> anyhow::Result<Option<(&'static str, Image)>> {
        let d = self.pass_data(gpu)?;
        let entered: Vec<bool> = match d.layers.first() {
            Some(l0) => l0.iter().map(|e| e.is_some()).collect(),
            None => vec![false; d.steps.len()],
        };
        Ok(Some((
            "passes",
            crate::passmap::pass_map(
                d.width,
                d.height,
                self.settings.tiles,
                d.tile_size,
                &d.tile_passes,
                &entered,
            ),
        )))
    }

    fn tile_counts(&mut self, _gpu: &Gpu) -> anyhow::Result<Option<render_core::TileCounts>> {
        let st = self.state()?;
        let (Some(t), Some(last)) = (&st.target, &st.last) else {
            bail!("raycast: render before tile_counts");
        };
        Ok(Some(crate::passmap::tile_counts(
            [t.width, t.height],
            self.settings.tiles,
            last.tile_size,
            &last.tile_passes,
        )))
    }
}

/// One frame, phase by phase as §3.2 of Bernardon et al. (2005) orders them (its Fig. 4): the
/// viewport's buffers and the frame's parameters, phases 1–2 (the first hit and the peeling
/// layers, [`peel`]), phase 3 (the ray-casting passes and their counts per tile, [`cast`]), and
/// the counters. Phase 4, the colour, is [`Renderer::read_image`]'s readback.
fn frame(
    gpu: &Gpu,
    st: &mut State,
    s: &RaycastSettings,
    camera: &Camera,
) -> anyhow::Result<FrameStats> {
    let slots = s.max_layers + 1;
    fit_target(gpu, st, camera, slots)?;
    let t = st.target.as_ref().expect("target fitted above");
    let (tile_size, rects) = tile_rects(camera.width, camera.height, s.tiles);
    let mut clock = FrameClock::start();
    gpu.queue
        .write_buffer(&t.tile_rects, 0, bytemuck::cast_slice(&rects));
    let mut params = frame_params(st, s, camera, tile_size);
    gpu.queue
        .write_buffer(&st.frame_params, 0, bytemuck::bytes_of(&params));
    let peeled = peel(gpu, st, t, s, slots, &mut clock)?;
    // Rays start at their first entry; active rays are counted per tile.
    params.counts[1] = peeled.layers;
    params.counts[3] = cast_flags(s, peeled.dropped_check);
    let cast = cast(gpu, st, t, s, &params, &mut clock)?;
    let times = clock.finish();
    let gpu_ms = st.timer.gpu_ms(gpu)?;
    let counters = counters(st, s, &peeled, &cast);
    st.last = Some(LastFrame {
        camera: camera.clone(),
        layers_used: peeled.layers,
        tile_passes: cast.tile_passes,
        tile_size,
    });
    Ok(times.stats(gpu_ms, st.ledger.per_frame + st.target_bytes, counters))
}

/// Makes `st.target` the buffers of `camera`'s viewport with `slots` layer slots, if it is not.
fn fit_target(gpu: &Gpu, st: &mut State, camera: &Camera, slots: u32) -> anyhow::Result<()> {
    let (w, h) = (camera.width, camera.height);
    if st
        .target
        .as_ref()
        .is_some_and(|t| t.width == w && t.height == h)
    {
        return Ok(());
    }
    st.target = None;
    let mut target_ledger = MemoryLedger::default();
    let target = Target::new(gpu, &st.pipes, &mut target_ledger, &st.table, w, h, slots)?;
    st.target = Some(target);
    st.target_bytes = target_ledger.per_frame;
    Ok(())
}

/// The frame's parameters for the peel: the rays in object coordinates, the projection, the
/// viewport and tiles, the bias and the table. The cast's layer count and flags are 0 here.
fn frame_params(
    st: &State,
    s: &RaycastSettings,
    camera: &Camera,
    tile_size: [u32; 2],
) -> FrameParams {
    let rf = RayFrame::new(camera, st.origin);
    let p4 = |v: [f32; 3]| [v[0], v[1], v[2], 0.0];
    let model = glam::DMat4::from_translation(glam::DVec3::from(st.origin));
    let vp: glam::Mat4 = (camera.view_proj() * model).as_mat4();
    // λ of the farthest point any ray can reach inside the fitted frustum (slightly beyond far).
    let lambda_far = camera.far * 2.0;
    FrameParams {
        o0: p4(rf.o0),
        ox: p4(rf.ox),
        oy: p4(rf.oy),
        d0: p4(rf.d0),
        dx: p4(rf.dx),
        dy: p4(rf.dy),
        view_proj: vp.to_cols_array_2d(),
        size: [camera.width, camera.height, tile_size[0], tile_size[1]],
        counts: [s.tiles, 0, st.max_steps, 0],
        misc: [
            (1.0 / lambda_far) as f32,
            (PEEL_BIAS * st.length_unit) as f32,
            ET_OPACITY,
            st.inv_table_length,
        ],
        table: [TABLE_SCALAR as u32, TABLE_LENGTH as u32, s.max_layers, 0],
    }
}

/// The cast's flags: early termination, the 3D table, counting the dropped re-entries where
/// the peel drew the spare slot, and the unscaled 2D table of the positive control.
fn cast_flags(s: &RaycastSettings, dropped_check: bool) -> u32 {
    let flag = |on: bool, bit: u32| if on { bit } else { 0 };
    flag(s.early_termination, FLAG_ET)
        | flag(s.table == TableKind::ThreeD, FLAG_TABLE3D)
        | flag(dropped_check, FLAG_COUNT_DROPPED)
        | flag(s.unscaled, FLAG_UNSCALED)
}

/// Submits one dispatch of `pipeline` over the mesh and the traversal (a plain pass's flag).
fn dispatch(
    gpu: &Gpu,
    st: &State,
    t: &Target,
    pipeline: &wgpu::ComputePipeline,
    [x, y, z]: [u32; 3],
    clock: &mut FrameClock,
) {
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &st.mesh_bind, &[]);
        pass.set_bind_group(1, &t.cast_binds[0], &[]);
        pass.dispatch_workgroups(x, y, z);
    }
    clock.submit(gpu, [enc.finish()]);
}

/// The tiles that still have active rays, from their counts.
fn active_tiles(counts: &[u32]) -> Vec<u32> {
    (0..counts.len() as u32)
        .filter(|&i| counts[i as usize] > 0)
        .collect()
}

/// The first `n` per-tile counts of `buf`.
fn read_counts(
    gpu: &Gpu,
    clock: &mut FrameClock,
    buf: &wgpu::Buffer,
    n: usize,
) -> anyhow::Result<Vec<u32>> {
    let b = clock.read_buffer(gpu, buf, 0, n as u64 * 4)?;
    Ok(bytemuck::cast_slice(&b).to_vec())
}
