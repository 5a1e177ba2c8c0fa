//! One fragment-PT frame, timed with [`FrameClock`], in stages: the per-frame parameters,
//! pass 1, the visibility order (on the device, or made on the host and uploaded), pass 2, the
//! GPU times and the counters.

use std::time::Instant;

use anyhow::{anyhow, bail};
use render_core::bind::color_pass;
use render_core::sort;
use render_core::{Camera, FrameClock, FrameStats, Gpu};

use crate::classify::ZERO_AREA_REL;
use crate::{
    project_params, FragmentPtSettings, Pass1Params, Pass2Params, SortMode, State, EXP_ENTRIES,
    EXP_MAX_TAU, PSI_SIDE, TF_ENTRIES, WORKGROUP,
};

pub(crate) fn write_params(gpu: &Gpu, st: &State, camera: &Camera) {
    let p = project_params(st, camera);
    let p1 = Pass1Params {
        view_proj: p.view_proj,
        eye: [
            p.eye[0],
            p.eye[1],
            p.eye[2],
            if p.perspective { 1.0 } else { 0.0 },
        ],
        forward: [p.forward[0], p.forward[1], p.forward[2], 0.0],
        misc: [
            p.scalar_min,
            p.scalar_inv_range,
            p.inv_length_unit,
            ZERO_AREA_REL,
        ],
        counts: [st.tets, st.dispatch.0 * WORKGROUP, 0, 0],
    };
    gpu.queue
        .write_buffer(&st.pass1_params, 0, bytemuck::bytes_of(&p1));
    let p2 = Pass2Params {
        view_proj: p.view_proj,
        misc: [p.scalar_min, p.scalar_inv_range, EXP_MAX_TAU, 0.0],
        sizes: [TF_ENTRIES as u32, EXP_ENTRIES as u32, PSI_SIDE as u32, 0],
    };
    gpu.queue
        .write_buffer(&st.pass2_params, 0, bytemuck::bytes_of(&p2));
}

pub(crate) fn encode_pass1(
    enc: &mut wgpu::CommandEncoder,
    st: &State,
    ts: Option<(&wgpu::QuerySet, u32)>,
) {
    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some("fragment-pt pass 1"),
        timestamp_writes: ts.map(|(qs, i)| wgpu::ComputePassTimestampWrites {
            query_set: qs,
            beginning_of_pass_write_index: Some(i),
            end_of_pass_write_index: Some(i + 1),
        }),
    });
    pass.set_pipeline(&st.pass1);
    pass.set_bind_group(0, &st.pass1_bind, &[]);
    pass.dispatch_workgroups(st.dispatch.0, st.dispatch.1, 1);
}

/// Renders one frame into `st`'s target (created by the caller) and waits for the GPU.
pub(crate) fn render(
    gpu: &Gpu,
    st: &mut State,
    camera: &Camera,
    settings: &FragmentPtSettings,
) -> anyhow::Result<FrameStats> {
    let sort_mode = settings.sort;
    let mut clock = FrameClock::start();
    write_params(gpu, st, camera);
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    encode_pass1(&mut enc, st, st.queries.as_ref().map(|(q, _)| (q, 0)));
    match sort_mode {
        SortMode::Gpu => {
            // Everything on the device: pass 1 wrote the centroid depths (keys) and the tet
            // ids (payload); sort both in place, far to near, then draw. No readback.
            let gs = st
                .gpu_sort
                .as_ref()
                .ok_or_else(|| anyhow!("fragment-pt: GPU sort not prepared"))?;
            gs.encode(&mut enc, &st.depths, &st.order, st.tets, true)?;
        }
        _ => {
            clock.submit(gpu, [enc.finish()]);
            enc = gpu.device.create_command_encoder(&Default::default());
            host_order(gpu, st, camera, settings, &mut clock)?;
        }
    }
    encode_pass2(gpu, &mut enc, st);
    if let Some((q, buf)) = &st.queries {
        enc.resolve_query_set(q, 0..4, buf, 0);
    }
    clock.submit(gpu, [enc.finish()]);
    clock.wait(gpu)?;
    let times = clock.finish();
    let (gpu_ms, stages) = gpu_times(gpu, st, sort_mode)?;
    Ok(times.with_stages(stages).stats(
        gpu_ms,
        st.ledger.per_frame,
        counters(st, camera, sort_mode),
    ))
}

/// The visibility order made on the host (after pass 1, which the caller submitted) and
/// uploaded: the centroid depths read back (the paper's way; MPVONC needs none), sorted far
/// to near, or MPVONC's order.
fn host_order(
    gpu: &Gpu,
    st: &mut State,
    camera: &Camera,
    settings: &FragmentPtSettings,
    clock: &mut FrameClock,
) -> anyhow::Result<()> {
    let sort_mode = settings.sort;
    let t0 = Instant::now();
    let keys: Vec<f32> = if sort_mode == SortMode::Mpvonc {
        Vec::new()
    } else {
        // The paper reads the centroid depths pass 1 wrote back to the host (the wait for
        // pass 1 is not host work; the copy is).
        let bytes = clock.read_buffer(gpu, &st.depths, 0, st.tets as u64 * 4)?;
        bytemuck::cast_slice(&bytes).to_vec()
    };
    clock.stage("readback", t0);
    let t1 = Instant::now();
    match sort_mode {
        SortMode::Bucket => {
            // The paper's about 20 slabs (§4), unless a positive control perturbs them.
            let slabs = settings.bucket_slabs();
            sort::bucket_sort_indices(&keys, slabs, true, &mut st.indices);
        }
        SortMode::Merge => sort::merge_sort_indices(&keys, true, &mut st.indices, &mut st.merge),
        SortMode::Radix => {
            sort::radix_sort_indices_descending(&keys, &mut st.indices, &mut st.radix)
        }
        SortMode::Mpvonc => {
            let v = st
                .visibility
                .as_mut()
                .ok_or_else(|| anyhow!("fragment-pt: MPVONC not prepared"))?;
            v.back_to_front(&st.mesh, camera, &mut st.indices);
        }
        SortMode::Gpu => bail!("fragment-pt: the GPU sort has no host order"),
    }
    if st.indices.len() != st.tets as usize {
        bail!(
            "fragment-pt: visibility order has {} entries for {} tets",
            st.indices.len(),
            st.tets
        );
    }
    clock.stage("sort", t1);
    let t2 = Instant::now();
    gpu.queue
        .write_buffer(&st.order, 0, bytemuck::cast_slice(&st.indices));
    clock.stage("upload", t2);
    Ok(())
}

/// Pass 2, the fans back to front, in passes of bounded size (render_core::bind::pass_slices),
/// the first clearing the target and the rest blending onto it; the timestamps bracket them
/// all.
fn encode_pass2(gpu: &Gpu, enc: &mut wgpu::CommandEncoder, st: &State) {
    let (_, view) = st.target.as_ref().expect("target created by the caller");
    let qs = st.queries.as_ref().map(|(q, _)| q);
    let slices = render_core::bind::pass_slices(0..st.tets * 12, gpu.triangles_per_pass);
    let last = slices.len() - 1;
    for (i, slice) in slices.into_iter().enumerate() {
        // wgpu refuses timestamp writes with neither index: middle passes take none.
        let timestamps =
            qs.filter(|_| i == 0 || i == last)
                .map(|q| wgpu::RenderPassTimestampWrites {
                    query_set: q,
                    beginning_of_pass_write_index: (i == 0).then_some(2),
                    end_of_pass_write_index: (i == last).then_some(3),
                });
        let mut pass = color_pass(enc, "fragment-pt pass 2", view, i == 0, true, timestamps);
        pass.set_pipeline(&st.pass2);
        pass.set_bind_group(0, &st.pass2_bind, &[]);
        render_core::bind::draw_in_slices(&mut pass, slice);
    }
}

/// Named stages of a frame and their milliseconds.
type Stages = Vec<(String, f64)>;

/// The frame's GPU milliseconds and its GPU stages, from the passes' timestamps (none
/// without timestamp queries).
fn gpu_times(gpu: &Gpu, st: &State, sort_mode: SortMode) -> anyhow::Result<(Option<f64>, Stages)> {
    let Some((_, buf)) = &st.queries else {
        return Ok((None, Vec::new()));
    };
    let b = gpu.read_buffer(buf, 0, 32)?;
    let t: &[u64] = bytemuck::cast_slice(&b);
    let period = gpu.queue.get_timestamp_period() as f64 * 1e-6;
    let pass1 = t[1].saturating_sub(t[0]) as f64 * period;
    let pass2 = t[3].saturating_sub(t[2]) as f64 * period;
    let mut stages = vec![("classify".to_string(), pass1), ("draw".to_string(), pass2)];
    let gpu_ms = if sort_mode == SortMode::Gpu {
        // One submission: pass 1, the device sort and pass 2 back to back.
        let all = t[3].saturating_sub(t[0]) as f64 * period;
        stages.push(("gpu_sort".to_string(), (all - pass1 - pass2).max(0.0)));
        all
    } else {
        // Two submissions with the host sort between them: the GPU time is the two passes'
        // timestamps.
        pass1 + pass2
    };
    Ok((Some(gpu_ms), stages))
}

/// The row's counters of a frame of `camera`.
fn counters(st: &mut State, camera: &Camera, sort_mode: SortMode) -> Vec<(String, f64)> {
    let per_tet = |x: f64| x / st.tets.max(1) as f64;
    let model_bytes_per_tet = per_tet(st.model_bytes as f64);
    let records_bytes_per_tet =
        per_tet(st.ledger.bytes_labelled("fragment-pt pass-1 records") as f64);
    let sort_bytes_per_tet = per_tet(
        (st.ledger.bytes_labelled("fragment-pt centroid depths")
            + st.ledger.bytes_labelled("fragment-pt order")) as f64,
    );
    let projected = st.fragments.get(camera, &st.mesh);
    let sorted_on = if sort_mode == SortMode::Gpu {
        "gpu_sort_keys"
    } else {
        "cpu_sort_keys"
    };
    vec![
        ("model_bytes_per_tet".to_string(), model_bytes_per_tet),
        // Drawn, but the projection is undefined for them (no near-plane clipping, as the
        // paper); counted outside the timed frame with the shaders' f32 matrix.
        (
            "tets_behind_eye".to_string(),
            camera.tets_behind_eye(&st.mesh) as f64,
        ),
        // Where the device bytes go (from the ledger, as allocated): the paper's 5.5 M tets on
        // a 256 MB board (§5) is judged on the total; these say which buffers take it.
        ("records_bytes_per_tet".to_string(), records_bytes_per_tet),
        ("sort_bytes_per_tet".to_string(), sort_bytes_per_tet),
        ("mesh_bindings".to_string(), st.mesh_bindings as f64),
        // The roofline's work: pass 2 draws 12 vertices (4 triangles) per tet, and the
        // visibility order covers every tet, on the device or on the host.
        ("triangles".to_string(), 4.0 * st.tets as f64),
        // Outside the timed frame, once per view: the pixel centres of every tet's projection,
        // which its fan covers once, and the tets that hold any.
        ("fragments".to_string(), projected.fragments as f64),
        ("covering_tets".to_string(), projected.covering_tets as f64),
        // Pass 1 classifies every tet once (one invocation per tet).
        ("tet_classifications".to_string(), st.tets as f64),
        (sorted_on.to_string(), st.tets as f64),
    ]
}
