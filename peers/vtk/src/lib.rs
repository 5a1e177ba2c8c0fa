//! VTK's unstructured-grid volume mappers as peers of tetbench's algorithms: the same mesh
//! (handed over as a `.vtu` written by [`datasets::write_vtu`]), camera, viewport and transfer
//! function, rendered offscreen by VTK through its Python package. Each is a configuration of
//! the external renderer client ([`external_peer::ExternalRenderer`]): the script
//! `vtk_peer.py` speaks the external renderer protocol (`docs/external-renderers.md`), so there
//! is one out-of-process mechanism, not two; the mapping of tetbench's conventions onto VTK's
//! lives in the script's header.
//!
//! Three algorithms, HAVS Table 5's classes (Callahan et al. 2005, §6):
//! * `vtk-pt` — `vtkProjectedTetrahedraMapper` (Shirley–Tuchman projected tetrahedra, cell
//!   centre depth sort);
//! * `vtk-raycast` — `vtkUnstructuredGridVolumeRayCastMapper` (Bunyk et al. ray casting),
//!   integrator as a setting;
//! * `vtk-zsweep` — `vtkUnstructuredGridVolumeZSweepMapper` (Farias et al. ZSweep).
//!
//! Every timed frame is a full re-render: the script turns the camera about the up axis by
//! ±0.01° on alternate frames, so no mapper can reuse a sort or a projection; the counters say
//! so (`camera_nudge_deg`). The image is read after one more render at the exact camera. VTK
//! reports no GPU memory, so peer rows have 0 persistent bytes and no GPU time.

pub mod process;

use std::time::Duration;

use anyhow::Context;
use datasets::TetMesh;
use external_peer::{ExternalRenderer, ExternalSpec};
use render_core::{
    Camera, DeclaredAccuracy, FrameStats, Gpu, Image, Optics, Prepared, Renderer, Settings,
};

mod description;
pub use description::{PT, RAYCAST, ZSWEEP};

/// How long one exchange with VTK may take: its float readout walks every pixel in Python.
pub const TIMEOUT: Duration = Duration::from_secs(600);

/// Which VTK mapper.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VtkMapper {
    ProjectedTetrahedra,
    RayCast,
    ZSweep,
}

impl VtkMapper {
    pub fn algorithm(self) -> &'static str {
        match self {
            VtkMapper::ProjectedTetrahedra => "vtk-pt",
            VtkMapper::RayCast => "vtk-raycast",
            VtkMapper::ZSweep => "vtk-zsweep",
        }
    }

    fn protocol_name(self) -> &'static str {
        match self {
            VtkMapper::ProjectedTetrahedra => "pt",
            VtkMapper::RayCast => "raycast",
            VtkMapper::ZSweep => "zsweep",
        }
    }

    /// VTK's class, for messages.
    pub fn class_name(self) -> &'static str {
        match self {
            VtkMapper::ProjectedTetrahedra => "vtkProjectedTetrahedraMapper",
            VtkMapper::RayCast => "vtkUnstructuredGridVolumeRayCastMapper",
            VtkMapper::ZSweep => "vtkUnstructuredGridVolumeZSweepMapper",
        }
    }
}

/// VTK's ray integrators (`vtkUnstructuredGrid*Integrator`), used by the ray caster and ZSweep.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Integrator {
    /// `vtkUnstructuredGridLinearRayIntegrator`: exact for linear attenuation and colour.
    Linear,
    /// `vtkUnstructuredGridPartialPreIntegration` (Moreland & Angel 2004).
    PartialPreIntegration,
    /// `vtkUnstructuredGridPreIntegration`: a pre-integrated table, nearest lookup.
    PreIntegration,
}

impl Integrator {
    pub const ALL: [Integrator; 3] = [
        Integrator::Linear,
        Integrator::PartialPreIntegration,
        Integrator::PreIntegration,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Integrator::Linear => "linear",
            Integrator::PartialPreIntegration => "partial-preintegration",
            Integrator::PreIntegration => "preintegration",
        }
    }
}

/// Where the ray caster's image comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Readout {
    /// The 8-bit framebuffer after VTK drew its image: what a VTK user sees.
    Framebuffer,
    /// VTK's own traversal and integrator per pixel, kept in float: the image before VTK stores
    /// it in 8 bits and draws it as a texture (ray caster only; used by the outside check).
    Rays,
}

impl Readout {
    pub fn name(self) -> &'static str {
        match self {
            Readout::Framebuffer => "framebuffer",
            Readout::Rays => "rays",
        }
    }
}

/// One VTK mapper with its settings.
pub struct VtkPeer {
    mapper: VtkMapper,
    integrator: Integrator,
    readout: Readout,
    /// Early ray termination of the float readout (`readout=rays`); VTK's mapper always stops
    /// a ray at α ≥ 0.99, checked after each batch of intersections.
    early_termination: bool,
    client: ExternalRenderer,
}

impl VtkPeer {
    pub fn new(mapper: VtkMapper, integrator: Integrator, readout: Readout, et: bool) -> VtkPeer {
        let settings = [
            ("mapper", mapper.protocol_name()),
            ("integrator", integrator.name()),
            ("readout", readout.name()),
            ("et", if et { "on" } else { "off" }),
        ];
        let python = process::python_interpreter();
        let spec = ExternalSpec {
            name: mapper.algorithm().to_string(),
            // The script is embedded and handed over as `-c`, so the binary needs nothing
            // beside it but Python with `vtk`.
            argv: vec![
                python.to_string_lossy().into_owned(),
                "-u".into(),
                "-c".into(),
                process::SCRIPT.into(),
            ],
            settings: settings
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
            env: vec![],
            timeout: TIMEOUT,
            mark_external: false,
        };
        VtkPeer {
            mapper,
            integrator,
            readout,
            early_termination: et,
            client: ExternalRenderer::new(spec),
        }
    }

    /// The VTK and Python versions the running script reported.
    pub fn versions(&self) -> Option<String> {
        self.client.hello().map(|h| h.version.clone())
    }
}

impl Renderer for VtkPeer {
    fn algorithm(&self) -> &'static str {
        self.mapper.algorithm()
    }

    fn settings(&self) -> Settings {
        description::settings_of(
            self.mapper,
            self.integrator,
            self.readout,
            self.early_termination,
        )
    }

    fn prepare(
        &mut self,
        _gpu: &Gpu,
        mesh: &std::sync::Arc<TetMesh>,
        optics: &Optics,
    ) -> anyhow::Result<Prepared> {
        self.client.prepare_mesh(mesh, optics).with_context(|| {
            format!(
                "VTK peer {} under {} could not set up the mesh; if VTK is missing: {}",
                self.mapper.class_name(),
                process::python_interpreter().display(),
                process::INSTALL_HINT
            )
        })
    }

    fn render(&mut self, _gpu: &Gpu, camera: &Camera) -> anyhow::Result<FrameStats> {
        self.client.render_camera(camera)
    }

    fn read_image(&mut self, _gpu: &Gpu) -> anyhow::Result<Image> {
        self.client.read_last_image()
    }

    /// What the script declared in its hello (the framebuffer readouts of the ray caster and
    /// ZSweep, see `vtk_peer.py`).
    fn declared_accuracy(&self) -> Option<DeclaredAccuracy> {
        self.client.declared_accuracy()
    }
}
