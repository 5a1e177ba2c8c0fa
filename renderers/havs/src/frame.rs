//! HAVS per frame: the per-viewport targets, and one frame in stages (object-space sort on
//! the host or the device, uniforms, clears, face raster into the k-buffers, drain, counters),
//! timed with [`FrameClock`] (one definition of `cpu_ms` for every renderer).

use std::time::Instant;

use anyhow::bail;
use rayon::prelude::*;
use render_core::bind::{buffer_range, whole, whole_from};
use render_core::gpu::Lifetime;
use render_core::sort::radix_sort_indices;
use render_core::{Camera, FrameClock, FrameStats, Gpu};

use super::{
    kbuffer, sort_key, HavsSettings, KeyUniforms, Mode, SortMode, State, TagScheme, Target,
    Uniforms, MESH_BINDING,
};

/// Which fragment program a frame draws with (`mode=fragment-race`; the race-free mode has one).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Draw {
    /// `fs_kbuffer`, the paper's program: what the timed frames run.
    Timed,
    /// `fs_kbuffer_counting`: the same with the row's per-pixel counts, once per view.
    Counting,
}

/// The row's counters from the GPU's `counters` words of a counting frame.
pub(super) fn gpu_counters(mode: Mode, c: &[u32; 8]) -> Vec<(String, f64)> {
    let mut counters = vec![
        ("fragments".to_string(), c[0] as f64),
        ("kbuffer_out_of_order".to_string(), c[1] as f64),
        // Fragments that reached an opaque pixel and were dropped before the k-buffer and
        // the table (early ray termination, §4).
        ("et_culled_fragments".to_string(), c[4] as f64),
    ];
    match mode {
        Mode::RaceFree => {
            counters.push(("lists_over_512".to_string(), c[2] as f64));
            counters.push(("nodes".to_string(), c[3] as f64));
        }
        // Fragments whose read-modify-write of their pixel another fragment overwrote (the
        // race the paper accepted, §4): shaded (an exact atomic count per pixel) less what
        // the racy per-pixel counts kept. 0 where fragments of a pixel run one after the
        // other (lavapipe); their k-buffer updates were lost too, so `fragments` is short
        // by this much. Counted in the view's counting frame, whose race is not the timed
        // frames' on a GPU.
        Mode::FragmentRace => {
            counters.push(("race_lost_updates".to_string(), c[5] as f64));
        }
    }
    counters
}

/// A target's per-pixel buffers beside the image: the k-buffer and the count of fragments
/// shaded (`mode=fragment-race`), or the list heads and the node pool (`mode=race-free`); the
/// other mode's buffers are 16-byte placeholders for the bindings.
struct PixelBuffers {
    kentries: wgpu::Buffer,
    heads: wgpu::Buffer,
    nodes: wgpu::Buffer,
    node_capacity: u64,
}

impl State {
    /// (Re)creates the per-frame buffers for a `w`×`h` viewport (and, in race-free mode, a node
    /// pool of `nodes` fragments).
    pub(super) fn ensure_target(
        &mut self,
        gpu: &Gpu,
        s: HavsSettings,
        w: u32,
        h: u32,
        nodes: Option<u64>,
    ) -> anyhow::Result<()> {
        if let Some(t) = &self.target {
            if t.width == w && t.height == h && nodes.is_none() {
                return Ok(());
            }
        }
        // Forget the previous target's bytes before counting the new one.
        self.ledger.entries.retain(|(label, life, bytes)| {
            let keep = !label.starts_with("havs target ");
            if !keep && *life == Lifetime::PerFrame {
                self.ledger.per_frame -= bytes;
            }
            keep
        });
        let npx = w as u64 * h as u64;
        let pixels = self.ledger.buffer(
            gpu,
            "havs target pixels",
            Lifetime::PerFrame,
            npx * 32,
            TARGET_USAGE,
        )?;
        let px = self.pixel_buffers(gpu, s, (w, h), nodes)?;
        let (_, dummy_view) = render_core::bind::render_target(
            gpu,
            &mut self.ledger,
            "havs target attachment",
            (w, h),
            wgpu::TextureFormat::R8Unorm,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        )?;
        let bind_groups = self.bind_groups(
            gpu,
            &[&pixels, &px.kentries, &self.counters, &px.heads, &px.nodes],
        );
        self.target = Some(Target {
            width: w,
            height: h,
            pixels,
            kentries: px.kentries,
            heads: px.heads,
            _nodes: px.nodes,
            node_capacity: px.node_capacity,
            dummy_view,
            bind_groups,
        });
        Ok(())
    }

    /// The per-pixel buffers of the settings' mode for a `w`×`h` target.
    fn pixel_buffers(
        &mut self,
        gpu: &Gpu,
        s: HavsSettings,
        (w, h): (u32, u32),
        nodes: Option<u64>,
    ) -> anyhow::Result<PixelBuffers> {
        let npx = w as u64 * h as u64;
        let max_binding = gpu.max_storage_binding();
        let mut buffer = |label: &str, bytes: u64| {
            self.ledger
                .buffer(gpu, label, Lifetime::PerFrame, bytes, TARGET_USAGE)
        };
        Ok(match s.mode {
            Mode::FragmentRace => {
                let bytes = npx * s.k as u64 * 8;
                if bytes > max_binding {
                    bail!("HAVS: a {w}x{h} k-buffer with k = {} needs {bytes} bytes, over one storage binding", s.k);
                }
                PixelBuffers {
                    kentries: buffer("havs target k-buffer", bytes)?,
                    // Every fragment shaded, counted per pixel with an atomic: the racy
                    // per-pixel counts (`Pixel.info`) lose updates on a GPU, and the
                    // difference is the frame's `race_lost_updates`.
                    heads: buffer("havs target fragments shaded per pixel", npx * 4)?,
                    nodes: buffer("havs target unused nodes", 16)?,
                    node_capacity: 0,
                }
            }
            Mode::RaceFree => {
                // Start from a pool of 8 fragments per pixel; `render` grows it when a view needs more.
                let cap = nodes.unwrap_or(npx * 8).max(1024);
                if cap * 16 > max_binding {
                    bail!(
                        "HAVS race-free mode: {cap} fragments need {} bytes of lists, over one storage binding ({max_binding}); \
                         use mode=fragment-race or a smaller image",
                        cap * 16
                    );
                }
                PixelBuffers {
                    kentries: buffer("havs target unused k-buffer", 16)?,
                    heads: buffer("havs target list heads", npx * 4)?,
                    nodes: buffer("havs target fragment lists", cap * 16)?,
                    node_capacity: cap,
                }
            }
        })
    }

    /// One bind group per chunk of the order: its uniforms and its slice of the order, the
    /// table, the target's `buffers` (bindings 6…10) and the mesh.
    fn bind_groups(&self, gpu: &Gpu, buffers: &[&wgpu::Buffer; 5]) -> Vec<wgpu::BindGroup> {
        let mesh = [
            self.verts.bind_entries(MESH_BINDING),
            self.faces
                .bind_entries(MESH_BINDING + self.verts.bindings()),
        ]
        .concat();
        self.chunks
            .iter()
            .zip(&self.uniforms)
            .map(|(range, ub)| {
                let order = buffer_range(
                    3,
                    &self.order,
                    range.start * 4,
                    (range.end - range.start).max(1) * 4,
                );
                let entries = [
                    vec![whole(0, ub), order],
                    self.table.bind_entries(4, 5).to_vec(),
                    whole_from(6, buffers),
                    mesh.clone(),
                ];
                gpu.bind_group("havs bind group", &self.pipes.layout, &entries.concat())
            })
            .collect()
    }

    /// One frame of `camera`, drawn with the timed program or the counting one; its stats
    /// (without the GPU's counts) and the GPU's `counters` words, which mean something only
    /// after a counting draw.
    pub(super) fn frame(
        &mut self,
        gpu: &Gpu,
        s: HavsSettings,
        camera: &Camera,
        draw: Draw,
    ) -> anyhow::Result<(FrameStats, [u32; 8])> {
        let mut clock = FrameClock::start();
        if s.sort == SortMode::CpuRadix {
            self.sort_on_cpu(gpu, &mut clock, camera);
        }
        // The per-pixel passes (k-buffer clear, drain) cover the rows and columns the mesh can
        // reach, rounded up to whole 8×8 workgroups; no fragment lands outside, and `pixels`
        // (the image) is still cleared whole. Rows left out keep stale k-buffer entries, which
        // no pass of this frame reads, and a later frame clears the rows it uses.
        let rect = camera.covered_rect(&self.bounds);
        let groups = (
            rect[2].saturating_sub(rect[0]).div_ceil(8),
            rect[3].saturating_sub(rect[1]).div_ceil(8),
        );
        self.write_uniforms(gpu, s, camera, rect);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        self.timer.begin(&mut enc);
        self.encode_gpu_sort(gpu, &mut enc, camera)?;
        self.encode_clears(&mut enc, s, rect[1]..rect[1] + 8 * groups.1);
        self.encode_faces(gpu, &mut enc, draw);
        self.encode_drain(&mut enc, groups);
        self.timer.end(&mut enc);
        clock.submit(gpu, [enc.finish()]);
        clock.wait(gpu)?;
        let times = clock.finish();
        let gpu_ms = self.timer.gpu_ms(gpu)?;
        // A timed frame's counters hold nothing: it is not read back.
        let c: [u32; 8] = match draw {
            Draw::Counting => {
                bytemuck::pod_read_unaligned(&gpu.read_buffer(&self.counters, 0, 32)?)
            }
            Draw::Timed => [0; 8],
        };
        self.last_frame_counted = draw == Draw::Counting;
        let counters = self.counters_of(camera);
        Ok((times.stats(gpu_ms, self.ledger.per_frame, counters), c))
    }

    /// Object space: sorts the faces front to back by centroid distance (§5.1) on the host
    /// and uploads the order.
    fn sort_on_cpu(&mut self, gpu: &Gpu, clock: &mut FrameClock, camera: &Camera) {
        let t = Instant::now();
        let eye = camera.eye.map(|c| c as f32);
        let fwd = camera.forward().map(|c| c as f32);
        let persp = camera.is_perspective();
        let cents = &self.centroids;
        self.keys.clear();
        self.keys
            .par_extend(cents.par_iter().map(|&c| sort_key(eye, fwd, persp, c)));
        clock.stage("keys", t);
        let t = Instant::now();
        radix_sort_indices(&self.keys, &mut self.sorted, &mut self.scratch);
        clock.stage("sort", t);
        let t = Instant::now();
        gpu.queue
            .write_buffer(&self.order, 0, bytemuck::cast_slice(&self.sorted));
        clock.stage("upload", t);
    }

    /// Every order chunk's uniforms for this view.
    fn write_uniforms(
        &self,
        gpu: &Gpu,
        s: HavsSettings,
        camera: &Camera,
        [x0, y0, _, _]: [u32; 4],
    ) {
        let (eye, forward) = shader_view(camera);
        let t = self.target.as_ref().expect("target ensured");
        let flags = (s.tags == TagScheme::Two) as u32 | ((s.early_termination as u32) << 1);
        for (range, ub) in self.chunks.iter().zip(&self.uniforms) {
            let u = Uniforms {
                view_proj: camera.view_proj_f32(),
                eye,
                forward,
                width: t.width,
                height: t.height,
                flags,
                base_face: range.start as u32,
                max_len: self.max_len,
                n_s: self.n_s as f32,
                n_l: self.n_l as f32,
                node_capacity: t.node_capacity.min(u32::MAX as u64) as u32,
                et_alpha: kbuffer::EARLY_TERMINATION_ALPHA,
                rect_x0: x0,
                rect_y0: y0,
                _pad: 0,
            };
            gpu.queue.write_buffer(ub, 0, bytemuck::bytes_of(&u));
        }
    }

    /// `sort=gpu-radix`: the face keys computed and radix-sorted on the device, the ids copied
    /// into the order. Nothing where the host sorted.
    fn encode_gpu_sort(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        camera: &Camera,
    ) -> anyhow::Result<()> {
        let Some(gs) = &self.gpu_sort else {
            return Ok(());
        };
        let (eye, forward) = shader_view(camera);
        let ku = KeyUniforms {
            eye,
            forward,
            faces: self.num_faces as u32,
            _pad: [0; 3],
        };
        gpu.queue
            .write_buffer(&gs.key_uniforms, 0, bytemuck::bytes_of(&ku));
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("havs keys"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&gs.key_pipeline);
            pass.set_bind_group(0, &gs.key_bind_group, &[]);
            let groups = self.num_faces.div_ceil(256) as u32;
            let max = gpu.limits.max_compute_workgroups_per_dimension;
            let (gx, gy) = if groups <= max {
                (groups, 1)
            } else {
                (max, groups.div_ceil(max))
            };
            pass.dispatch_workgroups(gx, gy, 1);
        }
        gs.sorter
            .encode(enc, &gs.keys, &gs.ids, self.num_faces as u32, false)?;
        enc.copy_buffer_to_buffer(&gs.ids, 0, &self.order, 0, self.num_faces * 4);
        Ok(())
    }

    /// Clears the image and the counters whole, and the per-pixel state of `rows`.
    fn encode_clears(
        &self,
        enc: &mut wgpu::CommandEncoder,
        s: HavsSettings,
        rows: std::ops::Range<u32>,
    ) {
        let t = self.target.as_ref().expect("target ensured");
        let rows = rows.start..rows.end.min(t.height);
        enc.clear_buffer(&t.pixels, 0, None);
        enc.clear_buffer(&self.counters, 0, None);
        if rows.is_empty() {
            return;
        }
        // Per pixel: k entries of 8 bytes (fragment race) and, in both modes, a u32 in `heads`
        // (the race-free list head, or the fragment race's count of fragments shaded).
        let mut row_buffers = vec![(4, &t.heads)];
        if s.mode == Mode::FragmentRace {
            row_buffers.push((s.k as u64 * 8, &t.kentries));
        }
        for (per_pixel, buffer) in row_buffers {
            let row_bytes = t.width as u64 * per_pixel;
            enc.clear_buffer(
                buffer,
                rows.start as u64 * row_bytes,
                Some(rows.len() as u64 * row_bytes),
            );
        }
    }

    /// The faces in sorted order into the k-buffers: chunks in order, each in passes of
    /// bounded size (render_core::bind::pass_slices). The faces stay in sorted order across
    /// chunk and pass boundaries, and the k-buffer lives in storage buffers, so a new pass
    /// (its dummy attachment cleared) continues it.
    fn encode_faces(&self, gpu: &Gpu, enc: &mut wgpu::CommandEncoder, draw: Draw) {
        let t = self.target.as_ref().expect("target ensured");
        let pipeline = match (draw, &self.pipes.counting) {
            (Draw::Counting, Some(counting)) => counting,
            _ => &self.pipes.draw,
        };
        for (range, bg) in self.chunks.iter().zip(&t.bind_groups) {
            let vertices = 0..((range.end - range.start) * 3) as u32;
            for slice in render_core::bind::pass_slices(vertices, gpu.triangles_per_pass) {
                let mut pass = render_core::bind::color_pass(
                    enc,
                    "havs faces",
                    &t.dummy_view,
                    true,
                    false,
                    None,
                );
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, bg, &[]);
                render_core::bind::draw_in_slices(&mut pass, slice);
            }
        }
    }

    /// The screen pass over `groups` 8×8 workgroups: drains what the k-buffers hold (or
    /// resolves the fragment lists) into the image.
    fn encode_drain(&self, enc: &mut wgpu::CommandEncoder, groups: (u32, u32)) {
        let t = self.target.as_ref().expect("target ensured");
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("havs drain"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipes.drain);
        pass.set_bind_group(0, &t.bind_groups[0], &[]);
        if groups.0 > 0 && groups.1 > 0 {
            pass.dispatch_workgroups(groups.0, groups.1, 1);
        }
    }

    /// The row's counters known without the GPU's counts.
    fn counters_of(&mut self, camera: &Camera) -> Vec<(String, f64)> {
        let mut counters = vec![("faces".to_string(), self.num_faces as f64)];
        // The roofline's work: every unique face is one triangle, and the sort orders them all.
        counters.push(("triangles".to_string(), self.num_faces as f64));
        // Outside the timed frame, once per view: the faces whose projection holds a pixel
        // centre, the triangles that yield fragments (each one costs the rasteriser more than
        // its setup; the roofline's `rasterisation` resource).
        let mesh = &self.host_mesh;
        let faces = self
            .face_work
            .get_or(camera, || render_core::silhouette::face_work(camera, mesh));
        counters.push(("covering_faces".to_string(), faces.covering_faces as f64));
        let sorted_on = if self.gpu_sort.is_some() {
            "gpu_sort_keys"
        } else {
            "cpu_sort_keys"
        };
        counters.push((sorted_on.to_string(), self.num_faces as f64));
        counters.push((
            "table_filter_nearest".to_string(),
            self.table_nearest as u8 as f64,
        ));
        counters.push((
            "mesh_bindings".to_string(),
            (self.verts.bindings() + self.faces.bindings()) as f64,
        ));
        counters
    }
}

/// The eye with the projection in `w` (1: perspective) and the view direction, in f32 as the
/// shaders read them.
fn shader_view(camera: &Camera) -> ([f32; 4], [f32; 4]) {
    let [x, y, z] = camera.eye.map(|c| c as f32);
    let [fx, fy, fz] = camera.forward().map(|c| c as f32);
    let persp = camera.is_perspective() as u32 as f32;
    ([x, y, z, persp], [fx, fy, fz, 0.0])
}

/// Usage of a target's storage buffers.
const TARGET_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

#[cfg(test)]
mod tests {
    use crate::{Havs, HavsSettings, Mode, SortMode};
    use datasets::TetMesh;
    use render_core::{
        Camera, Gpu, Image, Optics, Projection, Renderer, TransferFunction, Viewpoint,
    };

    fn render(
        gpu: &Gpu,
        r: &mut Havs,
        mesh: &std::sync::Arc<TetMesh>,
        cam: &Camera,
    ) -> (Image, Vec<(String, f64)>) {
        let tf = TransferFunction::preset("high-opacity").unwrap();
        r.prepare(gpu, mesh, &Optics::for_mesh(tf, mesh)).unwrap();
        let stats = r.render(gpu, cam).unwrap();
        assert!(stats.cpu_ms <= stats.total_ms, "{stats:?}");
        (r.read_image(gpu).unwrap(), stats.counters)
    }

    fn counter(c: &[(String, f64)], name: &str) -> f64 {
        c.iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("{name} in {c:?}"))
            .1
    }

    /// Vertex, face and order arrays split over several storage bindings (forced with 4 KiB
    /// bindings) give exactly the image of one binding each, for both sorts; the race-free mode
    /// makes the comparison deterministic. Early termination only moves fragments from
    /// `fragments` to `et_culled_fragments`.
    #[test]
    fn split_bindings_render_the_same_image() {
        let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
        let mesh = std::sync::Arc::new(datasets::generate::from_spec("box:1k", 1).unwrap());
        let vp = Viewpoint::new("oblique", [0.4, 0.6, 0.7]);
        let cam = Camera::fit(&mesh.bounds(), &vp, Projection::default(), 48, 48);
        for sort in [SortMode::CpuRadix, SortMode::GpuRadix] {
            let s = HavsSettings {
                sort,
                mode: Mode::RaceFree,
                ..Default::default()
            };
            let (whole, cw) = render(&gpu, &mut Havs::new(s), &mesh, &cam);
            let mut split_r = Havs::new(s).with_max_binding(4096);
            let (split, cs) = render(&gpu, &mut split_r, &mesh, &cam);
            assert_eq!(counter(&cw, "mesh_bindings"), 2.0);
            assert!(counter(&cs, "mesh_bindings") >= 5.0, "{cs:?}");
            let orders = split_r
                .ledger()
                .unwrap()
                .entries
                .iter()
                .filter(|e| e.0 == "havs uniforms")
                .count();
            assert!(orders >= 2, "the order buffer is bound in {orders} chunks");
            assert_eq!(whole.pixels, split.pixels, "{sort:?}");
            assert!(whole.pixels.iter().any(|p| p[3] > 0.1));
            et_only_moves_fragments(&gpu, &mesh, &cam, s, &cw);
        }
    }

    /// With early termination off, `s` renders `cam` with no culled fragment, and as many
    /// fragments as `with_et` (the counters of `s` with it on) has fragments and culled ones.
    fn et_only_moves_fragments(
        gpu: &Gpu,
        mesh: &std::sync::Arc<TetMesh>,
        cam: &Camera,
        s: HavsSettings,
        with_et: &[(String, f64)],
    ) {
        let (_, no_et) = render(
            gpu,
            &mut Havs::new(HavsSettings {
                early_termination: false,
                ..s
            }),
            mesh,
            cam,
        );
        assert_eq!(counter(&no_et, "et_culled_fragments"), 0.0);
        assert_eq!(
            counter(with_et, "fragments") + counter(with_et, "et_culled_fragments"),
            counter(&no_et, "fragments")
        );
    }

    /// The timed frames draw with the paper's program, which counts nothing; the first render
    /// of a view adds one counting frame. The two programs make the same image bit for bit
    /// (where fragments of a pixel run in order: lavapipe; on a GPU both race), the counts of
    /// a view are kept for its later frames, and a new view counts again. With early
    /// termination the counts move fragments from `fragments` to `et_culled_fragments`.
    #[test]
    fn timed_frames_count_nothing_and_keep_the_view_s_counts() {
        let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
        let mesh = std::sync::Arc::new(datasets::generate::from_spec("shell:2k", 1).unwrap());
        let views = [[0.4, 0.6, 0.7], [-0.8, 0.1, 0.3]];
        let cams: Vec<Camera> = views
            .iter()
            .map(|&d| {
                let vp = Viewpoint::new("oblique", d);
                Camera::fit(&mesh.bounds(), &vp, Projection::default(), 64, 64)
            })
            .collect();
        let mut r = Havs::new(HavsSettings::default());
        let (first, counted) = render(&gpu, &mut r, &mesh, &cams[0]);
        assert!(
            r.read_pixel_counts(&gpu).is_ok(),
            "the first render ends counting"
        );
        let timed = r.render(&gpu, &cams[0]).unwrap();
        let again = r.read_image(&gpu).unwrap();
        assert!(
            r.read_pixel_counts(&gpu).is_err(),
            "a second render of the view is one timed frame"
        );
        assert_eq!(first.pixels, again.pixels, "counting and timed programs");
        assert!(first.pixels.iter().any(|p| p[3] > 0.1));
        assert_eq!(counted, timed.counters);
        assert!(counter(&counted, "fragments") > 1000.0, "{counted:?}");

        let other = r.render(&gpu, &cams[1]).unwrap();
        assert!(r.read_pixel_counts(&gpu).is_ok(), "a new view counts again");
        assert_ne!(
            counter(&other.counters, "fragments"),
            counter(&counted, "fragments")
        );
        et_only_moves_fragments(&gpu, &mesh, &cams[0], HavsSettings::default(), &counted);
    }

    /// `covering_faces`, derived on the CPU (render_core::silhouette::face_work), counts the
    /// faces the GPU rasterises into fragments: the same derivation's fragments equal the
    /// GPU's count of rasterised fragments (early termination off) up to centres on a face's
    /// edge, and from this oblique view the faces that cover are at most the faces drawn (a
    /// face counted twice would break it) and more than half of them.
    #[test]
    fn covering_faces_are_the_faces_the_gpu_rasterises() {
        let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
        let mesh = std::sync::Arc::new(datasets::generate::from_spec("shell:2k", 1).unwrap());
        let vp = Viewpoint::new("oblique", [0.4, 0.6, 0.7]);
        let cam = Camera::fit(&mesh.bounds(), &vp, Projection::default(), 64, 64);
        let s = HavsSettings {
            early_termination: false,
            mode: Mode::RaceFree,
            ..Default::default()
        };
        let (_, c) = render(&gpu, &mut Havs::new(s), &mesh, &cam);
        let cpu = render_core::silhouette::face_work(&cam, &mesh);
        assert_eq!(counter(&c, "covering_faces"), cpu.covering_faces as f64);
        let gpu_fragments = counter(&c, "fragments");
        let off = (gpu_fragments - cpu.fragments as f64).abs() / gpu_fragments;
        assert!(off < 2e-3, "GPU {gpu_fragments} against CPU {cpu:?}");
        let faces = counter(&c, "faces");
        assert!(cpu.covering_faces as f64 <= faces, "{cpu:?} of {faces}");
        assert!(
            cpu.covering_faces as f64 > 0.5 * faces,
            "{cpu:?} of {faces}"
        );
    }
}
