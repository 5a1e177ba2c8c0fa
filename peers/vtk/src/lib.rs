//! VTK's unstructured-grid volume mappers as peers of tetbench's algorithms: the same mesh
//! (handed over as a `.vtu` written by [`datasets::write_vtu`]), camera, viewport and transfer
//! function, rendered offscreen by VTK through its Python package in one persistent process
//! per renderer ([`process`], the script `vtk_peer.py`).
//!
//! Three algorithms, HAVS Table 5's classes (Callahan et al. 2005, §6):
//! * `vtk-pt` — `vtkProjectedTetrahedraMapper` (Shirley–Tuchman projected tetrahedra, cell
//!   centre depth sort);
//! * `vtk-raycast` — `vtkUnstructuredGridVolumeRayCastMapper` (Bunyk et al. ray casting),
//!   integrator as a setting;
//! * `vtk-zsweep` — `vtkUnstructuredGridVolumeZSweepMapper` (Farias et al. ZSweep).
//!
//! Every timed frame is a full re-render: the camera is turned about the up axis by
//! ±[`NUDGE_DEG`] on alternate frames, so no mapper can reuse a sort or a projection; the
//! counters say so (`camera_nudge_deg`). The image is read after one more render at the exact
//! camera. VTK reports no GPU memory, so peer rows have 0 persistent bytes and no GPU time.

pub mod conventions;
pub mod process;

use std::time::Instant;

use anyhow::{anyhow, Context};
use datasets::TetMesh;
use render_core::{Camera, FrameStats, Gpu, Image, Optics, Prepared, Renderer, Setting};
use serde_json::json;

use conventions::{camera_request, vtk_transfer, PixelSampling};
use process::PeerProcess;

/// The camera turn (degrees, about the up axis) between consecutive timed frames.
pub const NUDGE_DEG: f64 = 0.01;

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
    process: Option<PeerProcess>,
    /// The `.vtu` handed to VTK.
    mesh_dir: Option<tempfile::TempDir>,
    frame: u64,
    last_camera: Option<Camera>,
}

impl VtkPeer {
    pub fn new(mapper: VtkMapper, integrator: Integrator, readout: Readout, et: bool) -> VtkPeer {
        VtkPeer {
            mapper,
            integrator,
            readout,
            early_termination: et,
            process: None,
            mesh_dir: None,
            frame: 0,
            last_camera: None,
        }
    }

    fn sampling(&self) -> PixelSampling {
        match self.mapper {
            VtkMapper::RayCast => PixelSampling::Corners,
            _ => PixelSampling::Centres,
        }
    }

    fn process(&mut self) -> anyhow::Result<&mut PeerProcess> {
        self.process
            .as_mut()
            .ok_or_else(|| anyhow!("VTK peer: render before prepare"))
    }

    /// The VTK and Python versions the running script reported.
    pub fn versions(&self) -> Option<String> {
        self.process.as_ref().map(|p| {
            format!(
                "VTK {} on Python {}",
                p.hello["vtk_version"].as_str().unwrap_or("?"),
                p.hello["python"].as_str().unwrap_or("?")
            )
        })
    }
}

/// `vtk-pt`'s variants (it has one).
pub fn pt_variants() -> Vec<Box<dyn Renderer>> {
    vec![Box::new(VtkPeer::new(
        VtkMapper::ProjectedTetrahedra,
        Integrator::Linear,
        Readout::Framebuffer,
        true,
    ))]
}

/// `vtk-raycast` by default: the linear integrator, framebuffer image.
pub fn raycast_default_variants() -> Vec<Box<dyn Renderer>> {
    vec![Box::new(VtkPeer::new(
        VtkMapper::RayCast,
        Integrator::Linear,
        Readout::Framebuffer,
        true,
    ))]
}

/// Every `vtk-raycast` variant: each integrator with the framebuffer image, and with the float
/// image with and without early termination.
pub fn raycast_all_variants() -> Vec<Box<dyn Renderer>> {
    let mut v: Vec<Box<dyn Renderer>> = vec![];
    for integrator in Integrator::ALL {
        for (readout, et) in [
            (Readout::Framebuffer, true),
            (Readout::Rays, true),
            (Readout::Rays, false),
        ] {
            v.push(Box::new(VtkPeer::new(
                VtkMapper::RayCast,
                integrator,
                readout,
                et,
            )));
        }
    }
    v
}

/// `vtk-zsweep` by default: the linear integrator.
pub fn zsweep_default_variants() -> Vec<Box<dyn Renderer>> {
    vec![Box::new(VtkPeer::new(
        VtkMapper::ZSweep,
        Integrator::Linear,
        Readout::Framebuffer,
        true,
    ))]
}

/// Every `vtk-zsweep` variant: one per integrator.
pub fn zsweep_all_variants() -> Vec<Box<dyn Renderer>> {
    Integrator::ALL
        .iter()
        .map(|&i| {
            Box::new(VtkPeer::new(
                VtkMapper::ZSweep,
                i,
                Readout::Framebuffer,
                true,
            )) as Box<dyn Renderer>
        })
        .collect()
}

impl Renderer for VtkPeer {
    fn algorithm(&self) -> &'static str {
        self.mapper.algorithm()
    }

    fn settings(&self) -> Vec<Setting> {
        match self.mapper {
            VtkMapper::ProjectedTetrahedra => vec![Setting::new("sort", "cell-centre")],
            VtkMapper::ZSweep => vec![Setting::new("integrator", self.integrator.name())],
            VtkMapper::RayCast => vec![
                Setting::new("integrator", self.integrator.name()),
                Setting::new("readout", self.readout.name()),
                Setting::new("et", if self.early_termination { "on" } else { "off" }),
            ],
        }
    }

    fn prepare(&mut self, _gpu: &Gpu, mesh: &TetMesh, optics: &Optics) -> anyhow::Result<Prepared> {
        if self.process.is_none() {
            self.process = Some(PeerProcess::start()?);
        }
        let dir = tempfile::Builder::new()
            .prefix("tetbench-vtk-mesh-")
            .tempdir()
            .context("cannot create a temporary directory for the .vtu")?;
        let vtu = dir.path().join("mesh.vtu");
        datasets::write_vtu::write_vtu(mesh, &vtu).map_err(|e| anyhow!("{e}"))?;
        let tf = vtk_transfer(optics);
        // A camera is needed before the first render; the real one comes with each frame.
        let request = json!({
            "cmd": "setup",
            "vtu": vtu,
            "mapper": self.mapper.protocol_name(),
            "integrator": self.integrator.name(),
            "points": tf.points,
            "unit_distance": tf.unit_distance,
            "width": 64,
            "height": 64,
        });
        let answer = self.process()?.request(&request).with_context(|| {
            format!(
                "VTK peer {} could not set up the mesh",
                self.mapper.class_name()
            )
        })?;
        let cells = answer["cells"].as_u64().unwrap_or(0);
        if cells != mesh.num_tets() as u64 {
            anyhow::bail!(
                "VTK read {cells} cells from {}, tetbench wrote {}",
                vtu.display(),
                mesh.num_tets()
            );
        }
        self.mesh_dir = Some(dir);
        self.frame = 0;
        Ok(Prepared {
            persistent_bytes: 0,
            tets: mesh.num_tets() as u64,
        })
    }

    fn render(&mut self, _gpu: &Gpu, camera: &Camera) -> anyhow::Result<FrameStats> {
        self.frame += 1;
        let nudge = if self.frame.is_multiple_of(2) {
            NUDGE_DEG
        } else {
            -NUDGE_DEG
        };
        let request = json!({
            "cmd": "render",
            "size": [camera.width, camera.height],
            "camera": camera_request(camera, self.sampling()),
            "nudge_deg": nudge,
        });
        let t0 = Instant::now();
        let answer = self.process()?.request(&request)?;
        let total_ms = t0.elapsed().as_secs_f64() * 1e3;
        let vtk_ms = answer["ms"].as_f64().unwrap_or(f64::NAN);
        self.last_camera = Some(camera.clone());
        Ok(FrameStats {
            // tetbench's own host work in the frame: the request and answer on the pipe.
            cpu_ms: (total_ms - vtk_ms).max(0.0),
            gpu_ms: None,
            total_ms,
            frame_bytes: 0,
            stages: vec![("vtk_render".into(), vtk_ms)],
            counters: vec![("camera_nudge_deg".into(), NUDGE_DEG)],
        })
    }

    fn read_image(&mut self, _gpu: &Gpu) -> anyhow::Result<Image> {
        let camera = self
            .last_camera
            .clone()
            .ok_or_else(|| anyhow!("VTK peer: read_image before render"))?;
        let path = self
            .mesh_dir
            .as_ref()
            .ok_or_else(|| anyhow!("VTK peer: read_image before prepare"))?
            .path()
            .join("image.f32");
        let request = json!({
            "cmd": "image",
            "size": [camera.width, camera.height],
            "camera": camera_request(&camera, self.sampling()),
            "readout": self.readout.name(),
            "early_termination": self.early_termination,
            "path": path,
        });
        self.process()?.request(&request)?;
        let bytes =
            std::fs::read(&path).with_context(|| format!("cannot read {}", path.display()))?;
        let n = (camera.width * camera.height) as usize;
        if bytes.len() != n * 16 {
            anyhow::bail!(
                "VTK peer image {} has {} bytes, expected {}",
                path.display(),
                bytes.len(),
                n * 16
            );
        }
        let pixels = bytes
            .chunks_exact(16)
            .map(|p| {
                let f = |i: usize| f32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]]);
                [f(0), f(4), f(8), f(12)]
            })
            .collect();
        Ok(Image {
            width: camera.width,
            height: camera.height,
            pixels,
        })
    }
}
