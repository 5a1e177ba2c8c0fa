//! One data set's measurements: the reference images per viewpoint, each variant prepared once
//! and timed over the viewpoints and rounds, and every row finished (metrics, images,
//! counters, host peak memory). The run loop in the parent module drives it.

use super::*;
use crate::results::{Failure, NamedValues, Stage};

pub(super) struct DatasetContext<'a> {
    pub(super) config: &'a RunConfig,
    gpu: &'a Gpu,
    /// A mesh, or voxels split into tets on first need (a variant that draws tets, the
    /// reference).
    data: &'a LazyDataset,
    optics: &'a Optics,
    pub(super) label: String,
    /// Reference image per viewpoint with its PNG path and lost-ray count (or why there is
    /// none), rendered on first need.
    references: HashMap<String, Result<(Image, String, u64), String>>,
    /// The reference renderer's per-mesh data (planes, boundary bins), built on the first
    /// cache miss and shared by every viewpoint (0.3 s per view saved on Blunt Fin).
    reference_mesh: Option<reference::Prepared<'a>>,
    /// Wall time of the last [`Self::reference`] call (ms): taken out of the row's
    /// `harness_ms`, since the reference is rendered once per view for every variant.
    reference_ms: f64,
}

/// What a renderer is prepared from: the voxels themselves, or the tets.
enum PrepareInput<'a> {
    Voxels(&'a datasets::VoxelVolume),
    Tets(&'a std::sync::Arc<datasets::TetMesh>),
}

/// The row's fixed parts, before measuring (everything measured starts empty).
fn base_row(ctx: &DatasetContext, renderer: &dyn Renderer, vp: &Viewpoint) -> Row {
    let c = ctx.config;
    let a = &ctx.gpu.adapter;
    Row {
        algorithm: renderer.algorithm().to_string(),
        settings: renderer.settings(),
        dataset: ctx.label.clone(),
        tets: ctx.data.num_tets() as u64,
        viewpoint: vp.name.clone(),
        width: c.width,
        height: c.height,
        adapter: a.name.clone(),
        backend: a.backend.clone(),
        frames: c.frames * c.rounds.max(1),
        warmup: c.warmup,
        transfer_function: c.tf_spec.clone(),
        projection: projection_name(&c.projection),
        device_type: a.device_type.clone(),
        driver: format!("{} {}", a.driver, a.driver_info).trim().to_string(),
        ..Row::default()
    }
}

/// Median of each named value over the frames (`name=value;…`, in first-seen order).
fn median_named(
    frames: &[FrameStats],
    pick: impl Fn(&FrameStats) -> &Vec<(String, f64)>,
) -> NamedValues {
    let mut names: Vec<String> = vec![];
    for f in frames {
        for (n, _) in pick(f) {
            if !names.contains(n) {
                names.push(n.clone());
            }
        }
    }
    names
        .iter()
        .map(|n| {
            let v: Vec<f64> = frames
                .iter()
                .flat_map(|f| pick(f).iter().filter(|(m, _)| m == n).map(|(_, v)| *v))
                .collect();
            let m = summarize(&v).map(|s| s.median).unwrap_or(f64::NAN);
            (n.clone(), m)
        })
        .collect()
}

impl<'a> DatasetContext<'a> {
    pub(super) fn new(
        config: &'a RunConfig,
        gpu: &'a Gpu,
        data: &'a LazyDataset,
        optics: &'a Optics,
        label: String,
    ) -> Self {
        DatasetContext {
            config,
            gpu,
            data,
            optics,
            label,
            references: HashMap::new(),
            reference_mesh: None,
            reference_ms: 0.0,
        }
    }

    fn images_dir(&self, vp: &Viewpoint) -> (PathBuf, String) {
        let rel = format!("images/{}/{}", slug(&self.label), viewpoint_slug(&vp.name));
        (self.config.out.join(&rel), rel)
    }

    /// The reference image for `vp`, its PNG's path relative to OUT and how many of its rays
    /// the reference lost (rendered or read from the cache on first need, then kept for every
    /// variant).
    fn reference(
        &mut self,
        vp: &Viewpoint,
        camera: &Camera,
        progress: &Progress,
    ) -> Result<(Image, String, u64), String> {
        if let Some(r) = self.references.get(&vp.name) {
            return r.clone();
        }
        progress.status(&format!("reference {} {}", self.label, vp.name));
        let (dir, rel) = self.images_dir(vp);
        let cache = &self.config.cache_dir;
        let (data, optics) = (self.data, self.optics);
        let prepared = &mut self.reference_mesh;
        let r = guarded("the reference renderer", || {
            let mesh = data.mesh()?;
            let r = match reference::read_cached_reference(mesh, optics, camera, cache) {
                Some(r) => r,
                None => prepared
                    .get_or_insert_with(|| reference::Prepared::new(mesh))
                    .render_cached_reference(optics, camera, cache)?,
            };
            std::fs::create_dir_all(&dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
            r.image.save_png(&dir.join("reference.png"))?;
            Ok((r.image, format!("{rel}/reference.png"), r.lost_rays))
        })
        .map_err(|e| format!("{} {}: {e:#}", self.label, vp.name));
        self.references.insert(vp.name.clone(), r.clone());
        r
    }

    /// Measures `renderers` on this data set in `config.rounds` passes. Every variant is
    /// prepared once; each pass then renders, variant after variant, `warmup` untimed and
    /// `frames` timed frames per viewpoint, so the samples of one row are taken at `rounds`
    /// moments seconds apart. On a shared or virtual machine the speed drifts by tens of per
    /// cent over seconds while the frames of one moment agree to a few per cent: samples from
    /// one moment are not independent, and `compare`'s test needs independent ones (asv
    /// interleaves its rounds for the same reason). The last pass also reads each image back
    /// and writes the row.
    pub(super) fn run_variants(
        &mut self,
        renderers: Vec<Box<dyn Renderer>>,
        writer: &mut ResultsWriter,
        progress: &mut Progress,
        outcome: &mut RunOutcome,
        control: &mut Option<super::control::RunControl>,
    ) -> anyhow::Result<()> {
        let c = self.config;
        let rounds = c.rounds.max(1);
        // Per prepared variant: renderer, what prepare gave, frames so far and the first
        // failure per viewpoint.
        let mut live = vec![];
        for renderer in renderers {
            live.extend(self.prepare_variant(renderer, writer, progress, outcome)?);
        }
        // `scripts/profile.sh` samples only from here on: the frames and the rows, not the
        // loading and preparing.
        let _profiled = super::perf_control::ProfiledSection::begin();
        for round in 0..rounds {
            if let Some(control) = control.as_mut() {
                control.take(&self.label, round, writer, progress);
            }
            let last = round + 1 == rounds;
            for v in live.iter_mut() {
                for (i, vp) in c.viewpoints.iter().enumerate() {
                    // A row's peak: the largest over its viewpoint's frames in every round and
                    // the final readback (and the prepare, for the first viewpoint).
                    let peak_reset = reset_host_peak();
                    if v.failed[i].is_none() {
                        let what = format!("{} {} {}", v.renderer.algorithm(), self.label, vp.name);
                        progress.activity(&if rounds > 1 {
                            format!("{what} (round {}/{rounds})", round + 1)
                        } else {
                            what
                        });
                        match self.time_frames(v.renderer.as_mut(), vp) {
                            Ok((f, between_frames_ms)) => {
                                v.frames[i].extend(f);
                                v.harness_ms[i] += between_frames_ms;
                            }
                            Err(e) => v.failed[i] = Some(format!("{e:#}")),
                        }
                    }
                    if last {
                        let f = std::mem::take(&mut v.frames[i]);
                        let finishing = Instant::now();
                        self.reference_ms = 0.0;
                        let mut row = self.finish_row(
                            v.renderer.as_mut(),
                            &v.prepared,
                            vp,
                            f,
                            v.failed[i].take(),
                            progress,
                            outcome,
                            &writer.file.rows,
                        );
                        let finish_ms = finishing.elapsed().as_secs_f64() * 1e3;
                        row.harness_ms =
                            Some(v.harness_ms[i] + (finish_ms - self.reference_ms).max(0.0));
                        v.peaks[i] = v.peaks[i].max(host_peak_bytes(peak_reset));
                        row.host_peak_bytes = v.peaks[i];
                        writer.push(row)?;
                    } else {
                        v.peaks[i] = v.peaks[i].max(host_peak_bytes(peak_reset));
                    }
                }
            }
        }
        if let Some(control) = control.as_mut() {
            control.take(&self.label, rounds, writer, progress);
        }
        Ok(())
    }

    /// Prepares one variant for the data set: the voxels to a voxel renderer, the tets (split
    /// on first need) to any other, the host memory peak taken around it. A variant that does
    /// not prepare gets a failed row per viewpoint, and `None`.
    fn prepare_variant(
        &mut self,
        mut renderer: Box<dyn Renderer>,
        writer: &mut ResultsWriter,
        progress: &mut Progress,
        outcome: &mut RunOutcome,
    ) -> anyhow::Result<Option<Variant>> {
        let views = self.config.viewpoints.len();
        let what = self.describe(renderer.as_ref());
        progress.activity(&format!("preparing {what}"));
        // A voxel renderer takes a voxel volume as it is; any other renderer needs the
        // tets, split on first need before the prepare's peak is reset, so that the split
        // (like loading) is not counted as the prepare's memory.
        let input = match self.data.voxels().filter(|_| renderer.draws_voxels()) {
            Some(volume) => Ok(PrepareInput::Voxels(volume)),
            None => guarded("splitting the volume into tets", || Ok(self.data.mesh()?))
                .map(PrepareInput::Tets),
        };
        // The first viewpoint's row carries the prepare's peak (host copies of the mesh).
        let peak_reset = reset_host_peak();
        let prepared = input.and_then(|input| {
            guarded("prepare", || match input {
                PrepareInput::Voxels(volume) => {
                    renderer.prepare_voxels(self.gpu, volume, self.optics)
                }
                PrepareInput::Tets(mesh) => renderer.prepare(self.gpu, mesh, self.optics),
            })
        });
        let prepare_peak = host_peak_bytes(peak_reset);
        match prepared {
            Ok(prepared) => {
                let mut peaks = vec![None::<u64>; views];
                peaks[0] = prepare_peak;
                Ok(Some(Variant {
                    renderer,
                    prepared,
                    frames: vec![Vec::<FrameStats>::new(); views],
                    failed: vec![None::<String>; views],
                    peaks,
                    harness_ms: vec![0.0; views],
                }))
            }
            Err(e) => {
                // Every viewpoint of this variant gets a row that says why it is empty.
                for vp in &self.config.viewpoints {
                    let mut row = base_row(self, renderer.as_ref(), vp);
                    row.error = Some(Failure::new(Stage::Prepare, format!("{e:#}")));
                    row.host_peak_bytes = prepare_peak;
                    progress.step(&format!("FAILED {what} {}: {}", vp.name, row.error_text()));
                    writer.push(row)?;
                    outcome.failed_rows += 1;
                }
                Ok(None)
            }
        }
    }

    fn describe(&self, renderer: &dyn Renderer) -> String {
        format!(
            "{} {} on {}",
            renderer.algorithm(),
            renderer.settings(),
            self.label
        )
    }

    /// The warm-up and timed frames of one viewpoint in one round, and the wall time (ms)
    /// between and around the timed frames that none of them counts (the harness's own
    /// overhead inside the timing loop, plus whatever a renderer does before its clock starts).
    fn time_frames(
        &mut self,
        renderer: &mut dyn Renderer,
        vp: &Viewpoint,
    ) -> anyhow::Result<(Vec<FrameStats>, f64)> {
        let c = self.config;
        let camera = Camera::fit(&self.data.bounds(), vp, c.projection, c.width, c.height);
        for _ in 0..c.warmup {
            guarded("render", || renderer.render(self.gpu, &camera))?;
        }
        let mut frames = Vec::with_capacity(c.frames as usize);
        let timed = Instant::now();
        for _ in 0..c.frames {
            frames.push(guarded("render", || renderer.render(self.gpu, &camera))?);
        }
        let loop_ms = timed.elapsed().as_secs_f64() * 1e3;
        let inside_frames: f64 = frames.iter().map(|f| f.total_ms).sum();
        Ok((frames, (loop_ms - inside_frames).max(0.0)))
    }

    /// The row of one viewpoint once all its rounds ran (`failure`: the first error of any).
    #[allow(clippy::too_many_arguments)]
    fn finish_row(
        &mut self,
        renderer: &mut dyn Renderer,
        prepared: &render_core::Prepared,
        vp: &Viewpoint,
        frames: Vec<FrameStats>,
        failure: Option<String>,
        progress: &mut Progress,
        outcome: &mut RunOutcome,
        rows_so_far: &[Row],
    ) -> Row {
        let what = self.describe(renderer);
        let mut row = base_row(self, renderer, vp);
        row.gpu_bytes_persistent = Some(prepared.persistent_bytes);
        let measured = match failure {
            Some(e) => Err(anyhow!(e)),
            None => self.measure(renderer, prepared, vp, frames, &mut row, progress),
        };
        if let Err(e) = measured {
            row.error = Some(Failure::new(Stage::Render, format!("{e:#}")));
            outcome.failed_rows += 1;
            progress.step(&format!("FAILED {what} {}: {}", vp.name, row.error_text()));
        } else if let Some(failure) = &row.error {
            // Measured, but without error metrics (the reference failed).
            outcome.failed_rows += 1;
            progress.step(&format!(
                "{what} {}: {:.2} ms, no reference: {}",
                vp.name,
                row.total_ms.unwrap_or(f64::NAN),
                failure
            ));
        } else {
            // Against the rows so far; the final flags are set once every row is in.
            row.suspect = crate::results::suspect::reason(&row, rows_so_far);
            progress.step(&format!(
                "{what} {}: {:.2} ms, {:.3} M tets/s, PSNR {}{}",
                vp.name,
                row.total_ms.unwrap_or(f64::NAN),
                row.tets_per_sec.unwrap_or(f64::NAN) * 1e-6,
                row.psnr_db
                    .map(|p| format!("{p:.2} dB"))
                    .unwrap_or_else(|| "-".into()),
                row.suspect
                    .as_ref()
                    .map(|why| format!("  SUSPECT: {why}"))
                    .unwrap_or_default()
            ));
        }
        row
    }

    /// Fills `row` from the timed frames of every round of one viewpoint and the image of
    /// its last frame (the renderer's target still holds it); images are written as PNGs
    /// beside the results.
    fn measure(
        &mut self,
        renderer: &mut dyn Renderer,
        prepared: &render_core::Prepared,
        vp: &Viewpoint,
        frames: Vec<FrameStats>,
        row: &mut Row,
        progress: &Progress,
    ) -> anyhow::Result<()> {
        let c = self.config;
        if let Some(problem) = frames.iter().find_map(frame_time_problem) {
            // A NaN would also make results.json unreadable (JSON has no NaN).
            anyhow::bail!("the renderer reported an impossible frame time: {problem}");
        }
        let camera = Camera::fit(&self.data.bounds(), vp, c.projection, c.width, c.height);
        let image = guarded("read_image", || renderer.read_image(self.gpu))?;

        let total = summarize(&frames.iter().map(|f| f.total_ms).collect::<Vec<_>>())
            .ok_or_else(|| anyhow!("no timed frames (--frames must be at least 1)"))?;
        let cpu = summarize(&frames.iter().map(|f| f.cpu_ms).collect::<Vec<_>>());
        // GPU time only when every frame has it (timestamp queries supported).
        let gpu_ms: Option<Vec<f64>> = frames.iter().map(|f| f.gpu_ms).collect();
        let gpu = gpu_ms.as_deref().and_then(summarize);
        let tets = row.tets as f64;
        row.total_ms = Some(total.median);
        row.total_ms_min = Some(total.min);
        row.total_ms_max = Some(total.max);
        row.cpu_ms = cpu.map(|s| s.median);
        row.cpu_ms_min = cpu.map(|s| s.min);
        row.cpu_ms_max = cpu.map(|s| s.max);
        row.gpu_ms = gpu.map(|s| s.median);
        row.gpu_ms_min = gpu.map(|s| s.min);
        row.gpu_ms_max = gpu.map(|s| s.max);
        if total.median > 0.0 {
            row.fps = Some(1000.0 / total.median);
            row.tets_per_sec = Some(tets / (total.median * 1e-3));
        }
        let frame_bytes = frames.iter().map(|f| f.frame_bytes).max().unwrap_or(0);
        row.gpu_bytes_frame = Some(frame_bytes);
        row.gpu_bytes = Some(prepared.persistent_bytes + frame_bytes);
        if tets > 0.0 {
            row.bytes_per_tet = Some(prepared.persistent_bytes as f64 / tets);
        }
        row.stages = median_named(&frames, |f| &f.stages);
        row.counters = median_named(&frames, |f| &f.counters);
        let racy = crate::algorithms::nondeterministic_counters(
            &row.algorithm,
            &row.settings,
            &row.device_type,
        );
        row.samples = crate::results::samples::FrameSamples::from_frames(&frames, racy);

        let (dir, rel) = self.images_dir(vp);
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()))?;
        let stem = format!(
            "{}__{}",
            slug(&row.algorithm),
            slug(&row.settings.to_string())
        );
        image.save_png(&dir.join(format!("{stem}.png")))?;
        row.image = format!("{rel}/{stem}.png");
        let exact = format!("{stem}.{}", crate::results::samples::IMAGE_EXTENSION);
        crate::results::samples::write_f32_image(&dir.join(&exact), &image)?;
        row.image_f32 = format!("{rel}/{exact}");
        row.image_hash = crate::results::samples::image_hash(&image);
        self.write_extras(renderer, &dir, &rel, &stem, row)?;

        if c.reference {
            let referencing = Instant::now();
            let reference = self.reference(vp, &camera, progress);
            self.reference_ms = referencing.elapsed().as_secs_f64() * 1e3;
            match reference {
                Ok((reference, ref_path, lost_rays)) => {
                    // Rays the reference could not follow to their end (0 on sound meshes).
                    row.counters.insert("reference_lost_rays", lost_rays as f64);
                    let e = metrics::compare(&image, &reference)?;
                    row.rmse = Some(e.rmse);
                    row.psnr_db = Some(e.psnr_db);
                    row.max_abs_error = Some(e.max_abs_error);
                    row.bad_pixel_share = Some(e.bad_pixel_share);
                    row.covered_pixels = Some(e.covered_pixels);
                    row.reference_image = ref_path;
                    let heat = metrics::heatmap(&image, &reference)?;
                    let path = dir.join(format!("{stem}.error.png"));
                    heat.save(&path)
                        .map_err(|e| anyhow!("cannot write {}: {e}", path.display()))?;
                    row.heatmap = format!("{rel}/{stem}.error.png");
                }
                Err(msg) => {
                    // The timing is still valid; the row stays, without error metrics.
                    row.error = Some(Failure::new(Stage::Reference, msg));
                }
            }
        }
        Ok(())
    }

    /// What a renderer keeps of its last frame besides the image, written beside it as
    /// `STEM.…` in `dir` (the folder `rel` names): its second picture (the ray caster's
    /// pass-count map) and its counts per screen tile, as numbers the row names.
    fn write_extras(
        &self,
        renderer: &mut dyn Renderer,
        dir: &std::path::Path,
        rel: &str,
        stem: &str,
        row: &mut Row,
    ) -> anyhow::Result<()> {
        if let Some((suffix, extra)) = guarded("extra_image", || renderer.extra_image(self.gpu))? {
            extra.save_png(&dir.join(format!("{stem}.{suffix}.png")))?;
        }
        if let Some(counts) = guarded("tile_counts", || renderer.tile_counts(self.gpu))? {
            row.tile_counts = crate::results::tile_counts::write(dir, rel, stem, &counts)?;
        }
        Ok(())
    }
}

/// What is wrong with a frame's times, if anything: every time finite and non-negative, and the
/// CPU part of a frame no longer than the frame (docs/results.md, "Result columns").
fn frame_time_problem(f: &FrameStats) -> Option<String> {
    let ok = |v: f64| v.is_finite() && v >= 0.0;
    if !ok(f.total_ms) {
        Some(format!("total_ms = {}", f.total_ms))
    } else if !ok(f.cpu_ms) {
        Some(format!("cpu_ms = {}", f.cpu_ms))
    } else if f.cpu_ms > f.total_ms {
        Some(format!("cpu_ms {} > total_ms {}", f.cpu_ms, f.total_ms))
    } else {
        f.gpu_ms
            .filter(|g| !ok(*g))
            .map(|g| format!("gpu_ms = {g}"))
    }
}

/// One prepared variant of a data set while its rounds run ([`DatasetContext::run_variants`]).
struct Variant {
    renderer: Box<dyn Renderer>,
    prepared: render_core::Prepared,
    /// Per viewpoint: the timed frames so far, the first failure, the host peak so far.
    frames: Vec<Vec<FrameStats>>,
    failed: Vec<Option<String>>,
    peaks: Vec<Option<u64>>,
    /// Per viewpoint: the harness's wall time outside the frames so far (ms).
    harness_ms: Vec<f64>,
}

/// Resets the kernel's peak-resident-set mark (VmHWM) of this process to its current resident
/// set (`5` into /proc/self/clear_refs, Linux ≥ 4.0); false where that is not possible.
fn reset_host_peak() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// The process's peak resident set since the last [`reset_host_peak`] (VmHWM of
/// /proc/self/status, in bytes): kept by the kernel, so a short spike between two samples is
/// not missed. `None` when the reset failed (the mark would be the whole run's) or on systems
/// without procfs.
fn host_peak_bytes(was_reset: bool) -> Option<u64> {
    if !was_reset {
        return None;
    }
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_vm_hwm(&status)
}

fn parse_vm_hwm(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let mut parts = line["VmHWM:".len()..].split_whitespace();
    let value: u64 = parts.next()?.parse().ok()?;
    match parts.next() {
        Some("kB") => Some(value * 1024),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn host_peak_follows_an_allocation_and_resets() {
        assert_eq!(
            parse_vm_hwm("Name:\tx\nVmHWM:\t  1234 kB\nVmRSS:\t 12 kB\n"),
            Some(1234 * 1024)
        );
        assert_eq!(parse_vm_hwm("VmRSS: 1 kB"), None);
        if !reset_host_peak() {
            return; // no procfs here: the column stays empty, as documented
        }
        let before = host_peak_bytes(true).expect("VmHWM after a reset");
        // 64 MiB touched page by page: the peak must rise by at least most of it.
        // black_box: an allocation that is never read may be optimised away.
        let block = std::hint::black_box(vec![1u8; 64 << 20]);
        let during = host_peak_bytes(true).unwrap();
        assert!(during >= before + (48 << 20), "{before} → {during}");
        assert_eq!(std::hint::black_box(&block)[block.len() / 2], 1);
        drop(block);
        assert!(reset_host_peak());
    }
}
