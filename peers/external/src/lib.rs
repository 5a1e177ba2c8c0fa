//! Renderers in other processes and languages, measured as peers of tetbench's algorithms
//! through the external renderer protocol (`docs/external-renderers.md`, version 1): one
//! process per renderer variant, JSON lines over its stdin/stdout, a timeout on every
//! exchange, the mesh as a `.vtu` or raw arrays, images as raw RGBA f32.
//!
//! [`ExternalRenderer`] implements [`render_core::Renderer`] over [`process::Process`];
//! [`ExternalSpec`] is what `--external NAME[settings]=COMMAND` asks for; VTK's peers
//! (`vtk-peer`) are configurations of it; [`conformance`] is `tetbench external check`.

pub mod conformance;
pub mod process;
pub mod protocol;

use std::collections::HashSet;
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use anyhow::{anyhow, Context};
use datasets::TetMesh;
use render_core::{
    Camera, DeclaredAccuracy, FrameStats, Gpu, Image, Optics, Prepared, Renderer, SettingValue,
    Settings,
};
use serde_json::{json, Value};

use process::{Failure, Process};
use protocol::Hello;

/// The setting that marks a row as an outside renderer's (`peer=external`).
pub const PEER_SETTING: (&str, &str) = ("peer", "external");

/// The default timeout of one exchange, in seconds (`--external-timeout`).
pub const DEFAULT_TIMEOUT_S: f64 = 120.0;

/// A name or key with the `'static` lifetime the [`Renderer`] trait's names have: the few
/// distinct names a run meets are kept for the life of the process (interned, so that building
/// the same renderer again does not leak again).
pub fn intern(s: &str) -> &'static str {
    static NAMES: Mutex<Option<HashSet<&'static str>>> = Mutex::new(None);
    let mut names = NAMES.lock().unwrap_or_else(|p| p.into_inner());
    let set = names.get_or_insert_with(HashSet::new);
    if let Some(&known) = set.get(s) {
        return known;
    }
    let leaked: &'static str = Box::leak(s.to_string().into_boxed_str());
    set.insert(leaked);
    leaked
}

/// How one renderer process is started and named.
#[derive(Debug, Clone, PartialEq)]
pub struct ExternalSpec {
    /// The algorithm name in rows.
    pub name: String,
    /// Program and arguments (no shell).
    pub argv: Vec<String>,
    /// Settings sent in the hello; the row's settings.
    pub settings: Vec<(String, String)>,
    /// Added to the process's environment.
    pub env: Vec<(String, String)>,
    /// The timeout of every exchange but `prepare` (which gets five times it).
    pub timeout: Duration,
    /// Rows carry `peer=external` first (renderers given with `--external`; the VTK peers
    /// are marked by name instead).
    pub mark_external: bool,
}

impl ExternalSpec {
    /// Parses `NAME=COMMAND` or `NAME[key=value;key=value]=COMMAND` (`--external`).
    pub fn parse(text: &str) -> anyhow::Result<ExternalSpec> {
        let usage = "expected NAME=COMMAND or NAME[key=value;…]=COMMAND, e.g. \
                     mine=\"python3 examples/external/python/renderer.py\"";
        let name_end = text
            .find(['=', '['])
            .ok_or_else(|| anyhow!("--external {text:?}: {usage}"))?;
        let name = text[..name_end].trim();
        let valid = |c: char| c.is_ascii_alphanumeric() || "-_.+".contains(c);
        if name.is_empty() || !name.chars().all(valid) {
            anyhow::bail!(
                "--external {text:?}: the name {name:?} must be letters, digits and - _ . + \
                 (it names the algorithm in rows and files); {usage}"
            );
        }
        let mut rest = &text[name_end..];
        let mut settings = vec![];
        if let Some(inner) = rest.strip_prefix('[') {
            let close = inner
                .find(']')
                .ok_or_else(|| anyhow!("--external {text:?}: no ']' after the settings"))?;
            let given = Settings::parse(&inner[..close])
                .map_err(|e| anyhow!("--external {text:?}: {e}"))?;
            for (k, v) in given.iter() {
                if k == PEER_SETTING.0 || !k.chars().all(valid) {
                    anyhow::bail!("--external {text:?}: {k:?} cannot be a setting's name");
                }
                settings.push((k.to_string(), v.to_string()));
            }
            rest = &inner[close + 1..];
        }
        let command = rest
            .strip_prefix('=')
            .ok_or_else(|| anyhow!("--external {text:?}: {usage}"))?;
        let argv =
            process::split_command(command).map_err(|e| anyhow!("--external {text:?}: {e}"))?;
        Ok(ExternalSpec {
            name: name.to_string(),
            argv,
            settings,
            env: vec![],
            timeout: Duration::from_secs_f64(DEFAULT_TIMEOUT_S),
            mark_external: true,
        })
    }

    /// The row's settings: the marker (if any), then the given settings.
    pub fn row_settings(&self) -> Settings {
        let mut v = Settings::new();
        if self.mark_external {
            v.set(PEER_SETTING.0, PEER_SETTING.1);
        }
        for (k, val) in &self.settings {
            v.set(k, SettingValue::infer(val));
        }
        v
    }
}

/// What prepare handed the process, kept so a fresh process can be brought to the same state
/// after a crash or a hang.
struct PreparedState {
    request: Value,
    tets: u64,
    /// Holds the mesh files (and the image) as long as the renderer.
    dir: tempfile::TempDir,
}

/// A renderer in another process.
pub struct ExternalRenderer {
    spec: ExternalSpec,
    name: &'static str,
    process: Option<Process>,
    hello: Option<Hello>,
    state: Option<PreparedState>,
    frames: u64,
    last_camera: Option<Camera>,
    /// Fresh processes started after one was lost.
    restarts: u64,
}

impl ExternalRenderer {
    pub fn new(spec: ExternalSpec) -> ExternalRenderer {
        ExternalRenderer {
            name: intern(&spec.name),
            spec,
            process: None,
            hello: None,
            state: None,
            frames: 0,
            last_camera: None,
            restarts: 0,
        }
    }

    pub fn spec(&self) -> &ExternalSpec {
        &self.spec
    }

    /// What the renderer said in its hello (after the first prepare).
    pub fn hello(&self) -> Option<&Hello> {
        self.hello.as_ref()
    }

    /// Fresh processes started after one was lost (crash, hang, protocol error).
    pub fn restarts(&self) -> u64 {
        self.restarts
    }

    fn label(&self) -> &str {
        &self.spec.name
    }

    /// Starts the process and says hello, unless one is running.
    fn ensure_started(&mut self) -> anyhow::Result<()> {
        if let Some(p) = self.process.as_mut() {
            if p.is_alive() {
                return Ok(());
            }
            self.restarts += 1;
        }
        self.process = None;
        let mut p = Process::spawn(self.label(), &self.spec.argv, &self.spec.env)?;
        let reply = p
            .exchange(
                &protocol::hello_request(&self.spec.settings),
                "hello",
                self.spec.timeout,
            )
            .map_err(|e| anyhow!("{e}"))?;
        let hello = protocol::parse_hello(self.label(), &reply, &self.spec.settings)?;
        self.process = Some(p);
        self.hello = Some(hello);
        Ok(())
    }

    fn exchange(
        &mut self,
        request: &Value,
        expect: &str,
        timeout: Duration,
    ) -> anyhow::Result<Value> {
        let p = self
            .process
            .as_mut()
            .ok_or_else(|| anyhow!("{}: no process (prepare first)", self.spec.name))?;
        p.exchange(request, expect, timeout)
            .map_err(|e: Failure| anyhow!("{e}"))
    }

    /// Sends `prepare` and checks the reply; returns the persistent bytes it reported.
    fn send_prepare(&mut self, request: &Value, tets: u64) -> anyhow::Result<u64> {
        let reply = self.exchange(request, "prepared", self.spec.timeout * 5)?;
        if let Some(t) = reply["tets"].as_u64() {
            if t != tets {
                anyhow::bail!(
                    "{} prepared {t} tets; tetbench handed it {tets}",
                    self.spec.name
                );
            }
        }
        Ok(reply["persistent_bytes"].as_u64().unwrap_or(0))
    }

    /// Hands the mesh and optics to the renderer (starting it if needed).
    pub fn prepare_mesh(&mut self, mesh: &TetMesh, optics: &Optics) -> anyhow::Result<Prepared> {
        self.ensure_started()?;
        let formats = self
            .hello
            .as_ref()
            .expect("hello after start")
            .formats
            .clone();
        let dir = tempfile::Builder::new()
            .prefix("tetbench-external-")
            .tempdir()
            .context("cannot create a temporary directory for the mesh")?;
        let request = json!({
            "type": "prepare",
            "mesh": protocol::write_mesh(mesh, &formats, dir.path())?,
            "optics": protocol::optics_json(optics),
        });
        self.state = None;
        let tets = mesh.num_tets() as u64;
        let persistent_bytes = self.send_prepare(&request, tets)?;
        self.state = Some(PreparedState { request, tets, dir });
        self.frames = 0;
        Ok(Prepared {
            persistent_bytes,
            tets,
        })
    }

    /// A fresh process brought back to the prepared mesh after the last one was lost, so a
    /// crash or hang fails one row, not the rest of the variant.
    fn ensure_ready(&mut self) -> anyhow::Result<()> {
        let alive = self.process.as_mut().is_some_and(Process::is_alive);
        if alive {
            return Ok(());
        }
        let (request, tets) = match &self.state {
            Some(s) => (s.request.clone(), s.tets),
            None => anyhow::bail!("{}: render before prepare", self.spec.name),
        };
        self.ensure_started()
            .and_then(|_| self.send_prepare(&request, tets))
            .map(|_| ())
            .with_context(|| format!("restarting {} after it was lost", self.spec.name))
    }

    /// Renders one frame; the exchange is timed here (see [`protocol::frame_stats`]).
    pub fn render_camera(&mut self, camera: &Camera) -> anyhow::Result<FrameStats> {
        self.ensure_ready()?;
        let hello = self.hello.as_ref().expect("hello after start");
        let (ok, which) = if camera.is_perspective() {
            (hello.perspective, "perspective")
        } else {
            (hello.orthographic, "orthographic")
        };
        if !ok {
            anyhow::bail!(
                "{} does not render {which} views (its hello's capabilities.projections)",
                self.spec.name
            );
        }
        self.frames += 1;
        let request = json!({
            "type": "render",
            "frame": self.frames,
            "camera": protocol::camera_json(camera),
        });
        self.last_camera = None;
        let t0 = Instant::now();
        let reply = self.exchange(&request, "rendered", self.spec.timeout)?;
        let exchange_ms = t0.elapsed().as_secs_f64() * 1e3;
        self.last_camera = Some(camera.clone());
        protocol::frame_stats(&self.spec.name, &reply, exchange_ms)
    }

    /// Asks for the last frame's image and reads it.
    pub fn read_last_image(&mut self) -> anyhow::Result<Image> {
        let camera = self
            .last_camera
            .clone()
            .ok_or_else(|| anyhow!("{}: read_image without a rendered frame", self.spec.name))?;
        let path: PathBuf = self
            .state
            .as_ref()
            .ok_or_else(|| anyhow!("{}: read_image before prepare", self.spec.name))?
            .dir
            .path()
            .join("image.f32");
        let _ = std::fs::remove_file(&path);
        let request = json!({
            "type": "read_image",
            "path": path,
            "width": camera.width,
            "height": camera.height,
        });
        self.exchange(&request, "image", self.spec.timeout)?;
        protocol::read_image_file(&self.spec.name, &path, camera.width, camera.height)
    }
}

impl Renderer for ExternalRenderer {
    fn algorithm(&self) -> &'static str {
        self.name
    }

    fn settings(&self) -> Settings {
        self.spec.row_settings()
    }

    fn prepare(
        &mut self,
        _gpu: &Gpu,
        mesh: &std::sync::Arc<TetMesh>,
        optics: &Optics,
    ) -> anyhow::Result<Prepared> {
        self.prepare_mesh(mesh, optics)
    }

    fn render(&mut self, _gpu: &Gpu, camera: &Camera) -> anyhow::Result<FrameStats> {
        self.render_camera(camera)
    }

    fn read_image(&mut self, _gpu: &Gpu) -> anyhow::Result<Image> {
        self.read_last_image()
    }

    fn declared_accuracy(&self) -> Option<DeclaredAccuracy> {
        self.hello.as_ref().and_then(|h| h.accuracy.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse_name_settings_and_command() {
        let s = ExternalSpec::parse("mine=python3 'my dir/r.py' --fast").unwrap();
        assert_eq!(s.name, "mine");
        assert_eq!(s.argv, ["python3", "my dir/r.py", "--fast"]);
        assert!(s.settings.is_empty());
        let s = ExternalSpec::parse("mine[step=0.5; grid=8]=./r --x=1").unwrap();
        assert_eq!(
            s.settings,
            [("step".into(), "0.5".into()), ("grid".into(), "8".into())]
        );
        assert_eq!(s.argv, ["./r", "--x=1"]);
        let row = s.row_settings();
        assert_eq!(row.to_string(), "peer=external;step=0.5;grid=8");
        assert_eq!(row.int("grid"), Some(8));
        for bad in [
            "mine",
            "=cmd",
            "mine=",
            "mi ne=cmd",
            "mine[step]=cmd",
            "mine[step=1=cmd",
            "mine='x",
        ] {
            assert!(ExternalSpec::parse(bad).is_err(), "{bad}");
        }
        assert!(ExternalSpec::parse("mine[peer=x]=cmd").is_err());
    }

    #[test]
    fn interned_names_are_shared() {
        let a = intern("some-renderer");
        let b = intern(&String::from("some-renderer"));
        assert!(std::ptr::eq(a, b));
    }
}
