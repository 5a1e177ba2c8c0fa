//! What the harness knows of VTK's three mappers without starting them (see
//! [`render_core::description`]).

use render_core::{
    AlgorithmDescription, Hue, Origin, Param, Renderer, Settings, Tolerance, ValueKind,
};

use crate::{Integrator, Readout, VtkMapper, VtkPeer};

const INTEGRATOR: Param = Param {
    key: "integrator",
    kind: ValueKind::Text,
    meaning: "VTK's ray integrator: linear, partial-preintegration or preintegration",
    section: "VTK's vtkUnstructuredGridVolume*Integrator classes",
};

pub static PT: AlgorithmDescription = AlgorithmDescription {
    name: "vtk-pt",
    title: "VTK's vtkProjectedTetrahedraMapper (peer)",
    origin: Origin::Peer("vtk"),
    params: &[Param {
        key: "sort",
        kind: ValueKind::Text,
        meaning: "VTK's own cell-centre depth sort (fixed)",
        section: "VTK's vtkProjectedTetrahedraMapper",
    }],
    default_grid: || {
        vec![settings_of(
            VtkMapper::ProjectedTetrahedra,
            Integrator::Linear,
            Readout::Framebuffer,
            true,
        )]
    },
    full_grid: || {
        vec![settings_of(
            VtkMapper::ProjectedTetrahedra,
            Integrator::Linear,
            Readout::Framebuffer,
            true,
        )]
    },
    build: |s| build(VtkMapper::ProjectedTetrahedra, s),
    hue: Hue::Greys,
    tolerance: |_| Tolerance {
        min_psnr_db: 45.0,
        why: "8-bit framebuffer and VTK's own approximations; see tests/vtk_vs_reference.rs",
    },
    counters: &[],
    nondeterministic_counters: render_core::description::all_counters_exact,
    deterministic: render_core::description::always_deterministic,
    gpu_layouts: render_core::gpu_layout::GpuLayouts::none,
    counter_evidence: &[],
    perturbations: &[],
};

pub static RAYCAST: AlgorithmDescription = AlgorithmDescription {
    name: "vtk-raycast",
    title: "VTK's vtkUnstructuredGridVolumeRayCastMapper (peer)",
    origin: Origin::Peer("vtk"),
    params: &[
        INTEGRATOR,
        Param {
            key: "readout",
            kind: ValueKind::Text,
            meaning: "framebuffer (VTK's displayed 8-bit image) or rays (its float result before display)",
            section: "ours (docs/external-renderers.md)",
        },
        Param {
            key: "et",
            kind: ValueKind::Text,
            meaning: "early ray termination (on/off; off only with readout=rays)",
            section: "VTK's mapper",
        },
    ],
    default_grid: || vec![settings_of(VtkMapper::RayCast, Integrator::Linear, Readout::Framebuffer, true)],
    full_grid: || {
        // Each integrator with the framebuffer image, and with the float image with and
        // without early termination.
        let mut v = vec![];
        for integrator in Integrator::ALL {
            for (readout, et) in [
                (Readout::Framebuffer, true),
                (Readout::Rays, true),
                (Readout::Rays, false),
            ] {
                v.push(settings_of(VtkMapper::RayCast, integrator, readout, et));
            }
        }
        v
    },
    build: |s| build(VtkMapper::RayCast, s),
    hue: Hue::Greys,
    tolerance: |_| Tolerance {
        min_psnr_db: 28.0,
        why: "the displayed image blurs silhouettes (the accuracy the peer declares)",
    },
    counters: &[],
    nondeterministic_counters: render_core::description::all_counters_exact,
    deterministic: render_core::description::always_deterministic,
    gpu_layouts: render_core::gpu_layout::GpuLayouts::none,
    counter_evidence: &[],
    perturbations: &[],
};

pub static ZSWEEP: AlgorithmDescription = AlgorithmDescription {
    name: "vtk-zsweep",
    title: "VTK's vtkUnstructuredGridVolumeZSweepMapper (peer)",
    origin: Origin::Peer("vtk"),
    params: &[INTEGRATOR],
    default_grid: || {
        vec![settings_of(
            VtkMapper::ZSweep,
            Integrator::Linear,
            Readout::Framebuffer,
            true,
        )]
    },
    full_grid: || {
        Integrator::ALL
            .iter()
            .map(|&i| settings_of(VtkMapper::ZSweep, i, Readout::Framebuffer, true))
            .collect()
    },
    build: |s| build(VtkMapper::ZSweep, s),
    hue: Hue::Greys,
    tolerance: |_| Tolerance {
        min_psnr_db: 28.0,
        why: "ZSweep rounds vertices to whole pixels (the accuracy the peer declares)",
    },
    counters: &[],
    nondeterministic_counters: render_core::description::all_counters_exact,
    deterministic: render_core::description::always_deterministic,
    gpu_layouts: render_core::gpu_layout::GpuLayouts::none,
    counter_evidence: &[],
    perturbations: &[],
};

pub(crate) fn settings_of(
    mapper: VtkMapper,
    integrator: Integrator,
    readout: Readout,
    early_termination: bool,
) -> Settings {
    match mapper {
        VtkMapper::ProjectedTetrahedra => Settings::new().with("sort", "cell-centre"),
        VtkMapper::ZSweep => Settings::new().with("integrator", integrator.name()),
        VtkMapper::RayCast => Settings::new()
            .with("integrator", integrator.name())
            .with("readout", readout.name())
            .with("et", early_termination),
    }
}

fn build(mapper: VtkMapper, s: &Settings) -> anyhow::Result<Box<dyn Renderer>> {
    let integrator = match s.text("integrator") {
        None => Integrator::Linear,
        Some(name) => Integrator::ALL
            .into_iter()
            .find(|i| i.name() == name)
            .ok_or_else(|| anyhow::anyhow!("{}: no integrator {name:?}", mapper.algorithm()))?,
    };
    let readout = match s.text("readout").as_deref() {
        None | Some("framebuffer") => Readout::Framebuffer,
        Some("rays") => Readout::Rays,
        Some(v) => anyhow::bail!(
            "{}: readout={v} is neither framebuffer nor rays",
            mapper.algorithm()
        ),
    };
    let et = match s.get("et") {
        None => true,
        Some(_) => s.require_switch("et")?,
    };
    Ok(Box::new(VtkPeer::new(mapper, integrator, readout, et)))
}
