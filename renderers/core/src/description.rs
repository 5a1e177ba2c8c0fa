//! What the harness knows of an algorithm without constructing it: its name, the paper it
//! reproduces or the package it comes from, its declared parameter grid, the constructor from
//! typed settings, its colour, its tolerance against the exact reference and the work
//! counters it reports. One [`AlgorithmDescription`] per algorithm crate; the harness lists
//! them in one table.

use crate::gpu_layout::GpuLayouts;
use crate::renderer::Renderer;
use crate::settings::{Settings, SettingsError, SettingsFilter, ValueKind};

/// One knob of the algorithm.
#[derive(Debug, Clone, Copy)]
pub struct Param {
    pub key: &'static str,
    pub kind: ValueKind,
    /// What the knob does, in a few words.
    pub meaning: &'static str,
    /// Where the paper describes it (`§3.2`), or where the choice is ours.
    pub section: &'static str,
}

/// Whether the algorithm is one of tetbench's own or another package's renderer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Origin {
    /// A tetbench algorithm reproducing a paper (the paper's id in `tetbench reproduce`).
    Paper(&'static str),
    /// Another package's renderer measured beside ours (`--peers GROUP`).
    Peer(&'static str),
}

/// The colour family of an algorithm's variants in every chart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Hue {
    Blues,
    Oranges,
    Greens,
    Purples,
    Magentas,
    Browns,
    Teals,
    /// Peers: grey with hollow markers.
    Greys,
}

/// How close a variant must come to the exact reference on the common check scene (a smooth
/// field on a structured grid, 128², the low-opacity transfer function; `tests/vs_reference.rs`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    pub min_psnr_db: f64,
    /// Why the bound is where it is (what was measured, what the margin covers).
    pub why: &'static str,
}

/// How an adapter shades the fragments that land on one pixel: one after the other in
/// primitive order (a CPU adapter such as lavapipe: one thread per screen tile), or
/// concurrently (a GPU). A counter that a race decides can differ between frames only where
/// the shading is concurrent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shading {
    InOrder,
    Concurrent,
}

impl Shading {
    /// The shading of an adapter by its wgpu device type (`Cpu` for a software rasteriser).
    pub fn of_device_type(device_type: &str) -> Shading {
        if device_type.eq_ignore_ascii_case("cpu") {
            Shading::InOrder
        } else {
            Shading::Concurrent
        }
    }
}

/// Where a counter's value comes from, when it is not measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CounterEvidence {
    /// An outcome of the frame the renderer could get wrong (the default: every counter not
    /// listed in [`AlgorithmDescription::counter_evidence`]).
    Measured,
    /// Follows from the data layout the renderer chose (bytes the layout reserves per tet):
    /// it equals the layout's arithmetic whatever the frame does.
    Layout,
    /// Follows from the draw call's own arguments (a fixed number of vertices per tet).
    DrawCall,
}

impl CounterEvidence {
    pub fn label(self) -> &'static str {
        match self {
            CounterEvidence::Measured => "measured",
            CounterEvidence::Layout => "follows from the data layout",
            CounterEvidence::DrawCall => "follows from the draw call",
        }
    }
}

/// For [`AlgorithmDescription::nondeterministic_counters`]: every counter is exact on every
/// adapter.
pub fn all_counters_exact(_: &Settings, _: Shading) -> &'static [&'static str] {
    &[]
}

/// For [`AlgorithmDescription::deterministic`]: every variant draws the same image, bit for
/// bit, frame after frame, on any adapter.
pub fn always_deterministic(_: &Settings, _: Shading) -> bool {
    true
}

/// What the harness knows of one algorithm.
pub struct AlgorithmDescription {
    /// Name on the command line and in result rows (`havs`).
    pub name: &'static str,
    /// A line for listings (`HAVS, Callahan et al. 2005`).
    pub title: &'static str,
    pub origin: Origin,
    /// Every knob, in the order settings are written.
    pub params: &'static [Param],
    /// The variants run when no `--settings` is given.
    pub default_grid: fn() -> Vec<Settings>,
    /// Every variant `--settings` selects from.
    pub full_grid: fn() -> Vec<Settings>,
    /// Builds the variant with these settings (every key declared, every value valid).
    pub build: fn(&Settings) -> anyhow::Result<Box<dyn Renderer>>,
    pub hue: Hue,
    pub tolerance: fn(&Settings) -> Tolerance,
    /// Names of the work counters each frame reports (`triangles`, `fragments`, `ray_steps`).
    pub counters: &'static [&'static str],
    /// The counters (of a variant, on an adapter that shades this way) that are not the same
    /// from frame to frame — a race decides them. `tetbench compare` tests these
    /// statistically; every other counter must match exactly.
    pub nondeterministic_counters: fn(&Settings, Shading) -> &'static [&'static str],
    /// Whether two frames of a variant, on an adapter that shades this way, give the same
    /// image bit for bit (where not, a race decides it); tests compare images only where so.
    pub deterministic: fn(&Settings, Shading) -> bool,
    /// The `#[repr(C)]` structs the algorithm uploads to the GPU and the WGSL they mirror
    /// (`tests/gpu_layouts.rs`); [`GpuLayouts::none`] for a renderer without any.
    pub gpu_layouts: fn() -> GpuLayouts,
    /// The counters of its rows that are not measured, with where they come from (the data
    /// layout, the draw call); every counter not listed is measured ([`Self::evidence_of`]).
    pub counter_evidence: &'static [(&'static str, CounterEvidence)],
    /// Keys that only perturb a variant on purpose, as the positive controls of the papers'
    /// image claims (the splatter's misaligned bricks): written only when set, selected by a
    /// filter and matched by a claim's side only where named ([`Self::select`]).
    pub perturbations: &'static [&'static str],
}

impl std::fmt::Debug for AlgorithmDescription {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AlgorithmDescription")
            .field("name", &self.name)
            .field("origin", &self.origin)
            .finish_non_exhaustive()
    }
}

impl AlgorithmDescription {
    /// The variants of `grid`, built.
    pub fn build_each(&self, grid: &[Settings]) -> anyhow::Result<Vec<Box<dyn Renderer>>> {
        grid.iter().map(|s| (self.build)(s)).collect()
    }

    /// The variants run when no `--settings` is given, built.
    pub fn default_variants(&self) -> anyhow::Result<Vec<Box<dyn Renderer>>> {
        self.build_each(&(self.default_grid)())
    }

    /// Every variant `--settings` selects from, built, in grid order.
    pub fn all_variants(&self) -> anyhow::Result<Vec<Box<dyn Renderer>>> {
        self.build_each(&(self.full_grid)())
    }

    pub fn is_peer(&self) -> bool {
        matches!(self.origin, Origin::Peer(_))
    }

    /// Where the counter `name` of its rows comes from.
    pub fn evidence_of(&self, name: &str) -> CounterEvidence {
        self.counter_evidence
            .iter()
            .find(|(n, _)| *n == name)
            .map_or(CounterEvidence::Measured, |(_, e)| *e)
    }

    pub fn param(&self, key: &str) -> Option<&Param> {
        self.params.iter().find(|p| p.key == key)
    }

    /// The declared type of `key`'s values.
    pub fn kind_of(&self, key: &str) -> Option<ValueKind> {
        self.param(key).map(|p| p.kind)
    }

    /// Parses this algorithm's settings text, typing each value as declared; a key the
    /// algorithm does not declare is an error.
    pub fn parse_settings(&self, text: &str) -> Result<Settings, SettingsError> {
        let s = Settings::parse_with(text, |k| self.kind_of(k))?;
        if let Some(k) = s.keys().find(|k| self.param(k).is_none()) {
            let known: Vec<&str> = self.params.iter().map(|p| p.key).collect();
            return Err(SettingsError(format!(
                "{} has no setting {k:?}; it has {}",
                self.name,
                known.join(", ")
            )));
        }
        Ok(s)
    }

    /// The variants `filter` selects, from the declared grid (no renderer is built). A key
    /// the filter names must take one of the listed values; a key it does not name keeps the
    /// values the default variants use. So no filter gives exactly the defaults, and `k=8`
    /// gives HAVS k = 8 with both sorts and otherwise default settings.
    pub fn select(&self, filter: &SettingsFilter) -> Vec<Settings> {
        let defaults = (self.default_grid)();
        if filter.is_empty() {
            return defaults;
        }
        let default_has = |key: &str, value: &str| defaults.iter().any(|d| d.is(key, value));
        // A filter naming a perturbation selects only the variants that carry it.
        let perturbs = |s: &Settings| {
            filter
                .terms
                .iter()
                .all(|(k, _)| !self.perturbations.contains(&k.as_str()) || s.get(k).is_some())
        };
        (self.full_grid)()
            .into_iter()
            .filter(|s| perturbs(s))
            .filter(|s| {
                s.iter().all(|(k, v)| {
                    let v = v.to_string();
                    match filter.values(k) {
                        Some(values) => values.contains(&v),
                        None => default_has(k, &v),
                    }
                })
            })
            .collect()
    }
}
